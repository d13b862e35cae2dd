"""The ``pymotoros_twin`` fixture used by the project's own tests, in process (issue 13):
the client drives the twin over real sockets; the marker picks the cell; the twin is
stopped after each test."""

from __future__ import annotations

import asyncio
import os
import socket
import subprocess
import sys
from pathlib import Path

import httpx
import pytest

from first_script import move_b_and_set_an_output
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
        move_b_and_set_an_output(robot, -0.3)
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


_LINTED_TESTS = '''
import socket
import struct

import pytest


def unknown_command(twin):
    """A MOTO_MOTION_CTRL with command 200199 (MotoROS knows no such command)."""
    frame = struct.pack("<7i10f", 64, 2001, 2, 0, 0, 0, 200199, *([0.0] * 10))
    with socket.create_connection((twin.host, twin.motion), timeout=5) as sock:
        sock.sendall(frame)
        sock.recv(100)


@pytest.mark.pymotoros(lint="error")
def test_dirty_fails(pymotoros_twin):
    unknown_command(pymotoros_twin)


@pytest.mark.pymotoros(lint="error")
def test_clean_passes(pymotoros_twin):
    assert pymotoros_twin.lint_findings() == []


def test_dirty_by_the_ini_option_fails(pymotoros_twin):
    unknown_command(pymotoros_twin)


@pytest.mark.pymotoros(lint="ignore")
def test_dirty_ignored_passes(pymotoros_twin):
    unknown_command(pymotoros_twin)
    assert sorted(str(f.code) for f in pymotoros_twin.lint_findings()) == [
        "stale-reply", "unknown-command"
    ]
'''


def test_lint_error_fails_a_test_with_findings(tmp_path: Path) -> None:
    """``@pytest.mark.pymotoros(lint="error")`` or ``pymotoros_lint = error`` in the ini
    file: a test whose client did something a robot answers differently fails with the
    findings; a clean one, and one marked ``lint="ignore"``, pass."""
    (tmp_path / "test_linted.py").write_text(_LINTED_TESTS)
    (tmp_path / "pytest.ini").write_text("[pytest]\npymotoros_lint = error\n")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src")}
    run = subprocess.run(  # noqa: S603 - our own interpreter and a test file we wrote
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tmp_path)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
        check=False,
    )
    out = run.stdout + run.stderr
    assert run.returncode == 1, out
    assert "2 failed, 2 passed" in out, out
    assert "FAILED test_linted.py::test_dirty_fails" in out, out
    assert "FAILED test_linted.py::test_dirty_by_the_ini_option_fails" in out, out
    assert "unknown-command" in out
    assert "fix: Send only the commands" in out


def test_the_twin_is_exact_by_default(pymotoros_twin: RunningTwin) -> None:
    assert pymotoros_twin.call(lambda c: c.fidelity) == "exact"


@pytest.mark.pymotoros(robot="gp7", fidelity="safe")
def test_fidelity_by_marker(pymotoros_twin: RunningTwin) -> None:
    """The marker's fidelity reaches the controller (and so the servers, which read it)."""
    assert pymotoros_twin.call(lambda c: c.fidelity) == "safe"
    assert pymotoros_twin.call(lambda c: c.cell.robots) == ("gp7",)


@pytest.mark.pymotoros(fidelity="safe", lint="error")
def test_fidelity_and_lint_in_one_marker(pymotoros_twin: RunningTwin) -> None:
    """The marker takes both settings together (neither is an unknown argument)."""
    assert pymotoros_twin.call(lambda c: c.fidelity) == "safe"
    assert pymotoros_twin.lint_findings() == []
