"""The ``pymotoros_twin`` fixture used by the project's own tests, in process (issue 13):
the client drives the twin over real sockets; the marker picks the cell; the twin is
stopped after each test."""

from __future__ import annotations

import asyncio
import socket
from pathlib import Path

import httpx
import pytest

from pymotoros.client import RobotClient, SyncRobotClient
from pymotoros.pytest_plugin import RunningTwin

CELLS = Path(__file__).resolve().parents[1] / "examples" / "cells"

TOLERANCE = 1e-3
"""Radians: where a finished move must end (a pulse is ~1e-5 rad; the stop is exact)."""


STATE_TIMEOUT_S = 5.0
"""Longest wait for the state stream to show a change (it runs at 25 Hz)."""


def options(twin: RunningTwin) -> dict[str, int]:
    return {"motion_port": twin.motion, "state_port": twin.state, "io_port": twin.io}


def test_the_blocking_client_moves_the_twin(pymotoros_twin: RunningTwin) -> None:
    with SyncRobotClient(pymotoros_twin.host, **options(pymotoros_twin)) as robot:
        robot.wait_for_state()
        robot.enable()
        result = robot.move_joints([0.0, 0.0, 0.0, 0.0, -0.3, 0.0])
        assert abs(result.final_positions[4] + 0.3) < TOLERANCE
        robot.write_io_bit(10020, 1)
        assert robot.read_io_bit(10020) == 1
    feedback = pymotoros_twin.call(lambda c: c.snapshot().groups[0].feedback_rad)
    assert feedback[4] == pytest.approx(-0.3, abs=TOLERANCE)


async def test_the_async_client_sees_the_operator_side(pymotoros_twin: RunningTwin) -> None:
    async with RobotClient(pymotoros_twin.host, **options(pymotoros_twin)) as robot:
        state = await robot.wait_for_state()
        assert state.status is not None
        assert not state.status.e_stopped
        pymotoros_twin.call(lambda c: c.press_estop(True))
        async with asyncio.timeout(STATE_TIMEOUT_S):
            async for state in robot.states():
                if state.status is not None and state.status.e_stopped:
                    break


@pytest.mark.pymotoros(cell=str(CELLS / "two_hc10_dx100.toml"))
def test_a_cell_file_by_marker(pymotoros_twin: RunningTwin) -> None:
    cell = pymotoros_twin.call(lambda c: c.cell)
    assert cell.name == "two arms on DX100"
    assert len(cell.groups) == 2


@pytest.mark.pymotoros(robot="gp7", controller="yrc1000", http=True)
def test_robot_names_and_the_control_api_by_marker(pymotoros_twin: RunningTwin) -> None:
    assert pymotoros_twin.http is not None
    state = httpx.get(f"http://127.0.0.1:{pymotoros_twin.http}/api/state", timeout=10).json()
    assert state["ports"]["motion"] == pymotoros_twin.motion
    assert pymotoros_twin.call(lambda c: c.cell.robots)[0].lower().startswith("gp7")


def test_without_http_there_is_no_control_api(pymotoros_twin: RunningTwin) -> None:
    assert pymotoros_twin.http is None
    with socket.create_connection(("127.0.0.1", pymotoros_twin.state), timeout=10) as sock:
        assert sock.recv(4096)


def test_the_twin_is_exact_by_default(pymotoros_twin: RunningTwin) -> None:
    assert pymotoros_twin.call(lambda c: c.fidelity) == "exact"


@pytest.mark.pymotoros(robot="gp7", fidelity="safe")
def test_fidelity_by_marker(pymotoros_twin: RunningTwin) -> None:
    """The marker's fidelity reaches the controller (and so the servers, which read it)."""
    assert pymotoros_twin.call(lambda c: c.fidelity) == "safe"
    assert pymotoros_twin.call(lambda c: c.cell.robots) == ("gp7",)
