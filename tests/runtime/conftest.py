"""Fixtures of the runtime tests: a simulator on 127.0.0.1 port 0 around a controller.

``app`` runs the real ``VirtualController`` (default cell: HC10 on a YRC1000) on the
real clock; ``vapp`` runs it on virtual time, as fast as the loop goes, for tests that
need controller seconds (servo power-up, trajectories). ``fake`` is a stand-in used
only where a test injects behaviour the real controller does not have (a crashing
tick, a state stream whose every cycle differs).
"""

from __future__ import annotations

from collections.abc import AsyncIterator

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.clock import ManualClock
from pymotoros.runtime.http_api import create_http_app

from .fake_controller import FakeController
from .support import LOCAL, STATS, cell_with_fidelity, virtual_time


@pytest.fixture
def controller(request: pytest.FixtureRequest) -> VirtualController:
    """The default cell, in the fidelity of the test's ``@pytest.mark.fidelity("safe")``
    marker (exact, the default, without one)."""
    return VirtualController(cell_with_fidelity(request))


@pytest.fixture
def fake() -> FakeController:
    return FakeController()


@pytest.fixture
async def app(controller: VirtualController) -> AsyncIterator[SimulatorApp]:
    """The virtual controller on the network, real clock, no HTTP."""
    async with SimulatorApp(controller, LOCAL) as sim:
        yield sim


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock()


@pytest.fixture
async def vapp(controller: VirtualController, clock: ManualClock) -> AsyncIterator[SimulatorApp]:
    """The virtual controller on virtual time (running as fast as the loop goes)."""
    async with SimulatorApp(controller, LOCAL, clock=clock) as sim, virtual_time(clock):
        yield sim


@pytest.fixture
async def api(controller: VirtualController) -> AsyncIterator[httpx.AsyncClient]:
    """An HTTP client of the control API in process (ASGI, no socket, no loop)."""
    app = create_http_app(controller, lambda: STATS)
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://sim") as client:
        yield client
