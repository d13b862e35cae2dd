"""Fixtures of the runtime tests: a simulator on 127.0.0.1 port 0 around a controller."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator

import pytest
from fake_controller import FakeController

from pymotoros.runtime.app import SimulatorApp, SimulatorConfig
from pymotoros.runtime.clock import ManualClock

LOCAL = SimulatorConfig(host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=None)


@pytest.fixture
def fake() -> FakeController:
    return FakeController()


@pytest.fixture
async def app(fake: FakeController) -> AsyncIterator[SimulatorApp]:
    """The fake controller on the network, real clock, no HTTP."""
    async with SimulatorApp(fake, LOCAL) as sim:
        yield sim


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
