"""Tests of "your robot software" against a twin each, as a user's CI would run them:

    cd examples/pytest_fleet && pytest -n 2

Here "your software" is a few raw Simple Message exchanges over plain sockets.
"""

from __future__ import annotations

import socket
import struct

import pytest

from pymotoros.pytest_plugin import RunningTwin

PING = struct.pack("<iiii", 12, 1, 2, 0)
"""A PING request (length prefix, msg type 1, comm type 2 = request, reply code 0)."""


def ping(port: int) -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.sendall(PING)
        return sock.recv(64)


def test_the_motion_port_answers_a_ping(pymotoros_twin: RunningTwin) -> None:
    reply = ping(pymotoros_twin.motion)
    assert struct.unpack("<iiii", reply[:16]) == (12, 1, 3, 1)  # a PING reply, SUCCESS


def test_the_state_port_streams(pymotoros_twin: RunningTwin) -> None:
    with socket.create_connection(("127.0.0.1", pymotoros_twin.state), timeout=10) as sock:
        assert len(sock.recv(4096)) > 0


def test_the_operator_side(pymotoros_twin: RunningTwin) -> None:
    pymotoros_twin.call(lambda controller: controller.press_estop(True))
    assert pymotoros_twin.call(lambda controller: controller.snapshot().estop)


@pytest.mark.pymotoros(robot="gp7", controller="yrc1000")
def test_another_robot(pymotoros_twin: RunningTwin) -> None:
    robots = pymotoros_twin.call(lambda controller: controller.cell.robots)
    assert robots[0].lower().startswith("gp7")


@pytest.mark.parametrize("k", range(4))
def test_many_twins_in_parallel(pymotoros_twin: RunningTwin, k: int) -> None:
    assert ping(pymotoros_twin.motion)
    assert len({pymotoros_twin.motion, pymotoros_twin.state, pymotoros_twin.io}) == 3, k
