"""Multi-group in the client: groups learnt from the state stream, names, cells, stop()."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
from slow_move import start_slow_move

from pymotoros.client import (
    ClientError,
    GroupError,
    ModelMismatchError,
    MoveStoppedError,
    RobotClient,
)
from pymotoros.controller.cell import load_cell
from pymotoros.models.cell import load_cell_models
from pymotoros.testing import Twin, sync_twin, twin
from says import assert_says

CELL = Path(__file__).resolve().parents[2] / "examples" / "cells" / "two_hc10_dx100.toml"
TOLERANCE = 1e-3


def test_the_cell_file_reads_the_same_in_client_and_simulator() -> None:
    models = load_cell_models(CELL)
    sim = load_cell(CELL)
    assert [g.name for g in models.robot.groups] == [g.name for g in sim.groups] == ["R1", "R2"]
    assert models.controller == sim.controller
    assert models.robots == sim.robots


async def test_a_model_with_more_groups_is_named_a_mismatch() -> None:
    async with Twin(robot="hc10") as the_twin:
        client = the_twin.client(robot="sda10f", timeout_s=2.0)
        async with client:
            with pytest.raises(ModelMismatchError) as info:
                await client.wait_for_state(2.0)
    assert_says(
        str(info.value),
        "model mismatch",
        "sda10f expects 4 group(s)",
        "streams 1 (group 0)",
        "R2",
        "--robot",
    )


async def test_a_model_with_fewer_axes_is_named_a_mismatch() -> None:
    cell = load_cell(CELL)
    async with Twin(cell) as the_twin:
        client = the_twin.client(robot="hc10", timeout_s=2.0)
        async with client:
            with pytest.raises(ModelMismatchError) as info:
                await client.wait_for_state(2.0)
    assert "also streams group(s) 1" in str(info.value)


@pytest.fixture
async def two_arms() -> AsyncIterator[tuple[RobotClient, Twin]]:
    async with twin(cell=load_cell(CELL), timeout_s=2.0) as pair:
        yield pair


async def test_group_names_and_numbers(two_arms: tuple[RobotClient, Twin]) -> None:
    client, _ = two_arms
    assert client.group_index("R2") == 1
    assert client.group_index("r1") == 0
    assert client.group_index("1") == 1
    with pytest.raises(GroupError, match=r"no group 'R3'.*R1 \(group 0, 6 axes\).*R2"):
        client.group_index("R3")
    with pytest.raises(GroupError, match="no group 2"):
        client.limits(2)


async def test_both_arms_in_one_trajectory(two_arms: tuple[RobotClient, Twin]) -> None:
    client, _ = two_arms
    await client.enable()
    r1 = (0.2, 0.3, 0.9, 0.0, -0.4, 0.1)
    r2 = (-0.2, -0.3, 0.8, 0.1, 0.4, 0.0)
    result = await client.move_joints({"R1": r1, "R2": r2})
    assert max(abs(a - b) for a, b in zip(r1 + r2, result.final_positions, strict=True)) < TOLERANCE
    result = await client.move_joints((*r1[:5], 0.5), group="R1")
    state = client.state
    assert abs((state.positions(0) or ())[5] - 0.5) < TOLERANCE
    assert max(abs(a - b) for a, b in zip(r2, state.positions(1) or (), strict=True)) < TOLERANCE


async def test_stop_from_another_task_ends_the_move_short(
    two_arms: tuple[RobotClient, Twin],
) -> None:
    client, the_twin = two_arms
    await client.enable()
    goal = (1.5, 0.5, 1.0, 0.0, -0.5, 0.0)
    started = asyncio.Event()
    move = asyncio.create_task(
        client.move_joints(goal, group="R1", on_progress=lambda s: started.set())
    )
    async with asyncio.timeout(5):
        await started.wait()
        await the_twin.sleep(0.3)
        await client.stop()
        with pytest.raises(MoveStoppedError) as info:
            await move
    assert info.value.positions[0] < goal[0] - 0.1
    assert str(info.value).startswith(
        "move stopped on request: the robot was stopped (STOP_MOTION) and stands at ["
    )
    assert str(info.value).count("STOP_MOTION") == 1  # said once
    assert info.value.early_stop is not None
    assert info.value.early_stop.positions == info.value.positions


def test_sync_stop_from_another_thread() -> None:
    with sync_twin(robot="hc10") as (client, _):
        client.enable()
        goal = (2.5, 0.0, 0.0, 0.0, 0.0, 0.0)
        move = start_slow_move(client, goal)
        client.stop()
        error = move.error()
        assert isinstance(error, MoveStoppedError)
        assert error.positions[0] < goal[0]


async def test_stop_threadsafe_from_a_thread_ends_an_async_move(
    two_arms: tuple[RobotClient, Twin],
) -> None:
    client, the_twin = two_arms
    await client.enable()
    goal = (-1.5, 0.5, 1.0, 0.0, -0.5, 0.0)
    started = asyncio.Event()
    move = asyncio.create_task(
        client.move_joints(goal, group=0, on_progress=lambda s: started.set())
    )
    async with asyncio.timeout(5):
        await started.wait()
        await the_twin.sleep(0.2)
        await asyncio.to_thread(client.stop_threadsafe)
        with pytest.raises(MoveStoppedError):
            await move
    with pytest.raises(ClientError, match="own loop"):
        client.stop_threadsafe()
