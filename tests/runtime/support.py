"""Shared helpers of the runtime tests (fixtures live in conftest.py)."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
from collections.abc import AsyncIterator

import pytest

from pymotoros.controller.cell import CellConfig, default_cell
from pymotoros.models.fidelity import Fidelity
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig
from pymotoros.runtime.clock import ManualClock
from pymotoros.runtime.ticker import LatenessStats, Ticker, TickStats

LOCAL = SimulatorConfig(host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=None)
"""Every listener on loopback port 0, no control API."""

STATS = TickStats(4.0, 1000, 2, 0, 0, LatenessStats(0.05, 0.2, 1.5))
"""Loop statistics for a control API built without a running loop."""


@contextlib.asynccontextmanager
async def virtual_time(clock: ManualClock) -> AsyncIterator[None]:
    """Run ``clock`` as fast as the loop goes for the duration of the block."""
    driver = asyncio.create_task(clock.run_virtual_time(), name="virtual-time")
    try:
        yield
    finally:
        driver.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await driver


def cell_with_fidelity(
    request: pytest.FixtureRequest, cell: CellConfig | None = None
) -> CellConfig:
    """``cell`` (the default cell) in the fidelity the test's ``@pytest.mark.fidelity(...)``
    names; without the marker, the cell's own (exact by default)."""
    cell = cell or default_cell()
    marker = request.node.get_closest_marker("fidelity")
    if marker is None:
        return cell
    return dataclasses.replace(cell, fidelity=Fidelity.parse(marker.args[0]))


async def settle() -> None:
    """Let woken tasks run (bounded number of loop turns)."""
    for _ in range(5):
        await asyncio.sleep(0)


@contextlib.asynccontextmanager
async def running(ticker: Ticker) -> AsyncIterator[asyncio.Task[None]]:
    """``ticker`` runs (as a task) for the duration of the block, then is cancelled."""
    task = asyncio.create_task(ticker.run(), name="ticker-under-test")
    await settle()
    try:
        yield task
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def until(
    app: SimulatorApp, what: str, condition: object, ticks: int = 2000, timeout_s: float = 10.0
) -> None:
    """Tick by tick until ``condition()`` holds (bounded in ticks and time)."""
    assert callable(condition)
    async with asyncio.timeout(timeout_s):
        for _ in range(ticks):
            if condition():
                return
            await app.ticker.wait_ticks(1)
    pytest.fail(f"{what} did not happen within {ticks} ticks")
