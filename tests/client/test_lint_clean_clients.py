"""Our own client gives the twin's client lint nothing to say in normal use (issue 31):
moves, named poses, a stop mid-move, IO, a two-arm cell; and ``Twin.assert_no_lint``
says what a client did wrong when it did."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from pymotoros.controller.cell import load_cell
from pymotoros.controller.lint import LintCode
from pymotoros.testing import twin

CELLS = Path(__file__).resolve().parents[2] / "examples" / "cells"


async def test_moves_a_stop_and_io_give_no_finding() -> None:
    async with twin(robot="hc10") as (client, cell):
        await client.enable()
        await client.move_joints([0.3, -0.2, 0.1, 0.0, -0.5, 0.2])
        await client.move_joints([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], speed_scale=0.5)
        moving = asyncio.create_task(client.move_joints([1.0, 0, 0, 0, 0, 0], speed_scale=0.2))
        await cell.sleep(0.5)
        await client.stop()
        await asyncio.gather(moving, return_exceptions=True)  # stopped on purpose
        await client.write_io_bit(10020, 1)
        assert await client.read_io_bit(10020) == 1
        await client.move_joints([0.1, 0, 0, 0, 0, 0])
        cell.assert_no_lint()
        assert cell.lint.findings() == []


async def test_two_arms_moving_together_give_no_finding() -> None:
    cell_config = load_cell(CELLS / "two_hc10_dx100.toml")
    async with twin(cell=cell_config) as (client, cell):
        await client.enable()
        await client.move_joints({0: [0.2, 0, 0, 0, -0.3, 0], 1: [-0.2, 0, 0, 0, 0.3, 0]})
        await client.move_joints({0: [0.0] * 6, 1: [0.0] * 6})
        cell.assert_no_lint()


async def test_assert_no_lint_tells_what_a_client_did() -> None:
    async with twin(robot="hc10") as (_client, cell):
        cell.lint.record(LintCode.SEQUENCE_NOT_CONSECUTIVE, "twin-client-1:0", 0.5, "point 3")
        with pytest.raises(AssertionError, match="sequence-not-consecutive") as caught:
            cell.assert_no_lint()
        assert "fix: Start each trajectory at sequence 0" in str(caught.value)
        cell.lint.clear()
        cell.assert_no_lint()
