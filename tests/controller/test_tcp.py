"""The TCP of the active tool in the snapshot: pose (base coordinates) and speed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.kinematics import chain_for
from pymotoros.models.robots import Transform

from .helpers import enter_traj_mode, point, send, start_at_current, tick_until

TOOL_TCP = (0.01, 0.02, 0.15)
TOOL_RPY = (0.0, 0.3, 0.0)


def _cell() -> VirtualController:
    cell = cell_from_dict(
        {
            "groups": [
                {
                    "robot": "hc10",
                    "tools": [{"number": 5, "tcp_m": list(TOOL_TCP), "rpy_rad": list(TOOL_RPY)}],
                }
            ],
            "initial": {"servo": True},
        }
    )
    return VirtualController(cell)


def test_tool_zero_tcp_is_tool0_in_base_coordinates() -> None:
    vc = _cell()
    tcp = vc.snapshot().groups[0].tcp
    assert tcp is not None
    # HC10 folded at zero (robot-models.md §1.2): tool0 0.162 m sideways, 0.07 m above base.
    assert tcp.command[:3] == pytest.approx((0.0, 0.162, 0.700 - 0.500 - 0.130), abs=1e-9)
    assert abs(tcp.command[3]) == pytest.approx(math.pi)
    assert tcp.feedback == pytest.approx(tcp.command)
    assert tcp.command_speed_mm_s == 0.0


def test_select_tool_moves_the_tcp_by_the_tool_offset() -> None:
    vc = _cell()
    assert vc.select_tool(0, 5).ok
    tcp = vc.snapshot().groups[0].tcp
    assert tcp is not None
    # tool0 points down (rolled by π): the tool's +z goes to −z of base, +y to −y.
    assert tcp.command[:3] == pytest.approx((0.01, 0.162 - 0.02, 0.07 - 0.15), abs=1e-9)
    expected = chain_for("hc10", Transform(TOOL_TCP, TOOL_RPY)).pose([0.0] * 6)
    assert tcp.command == pytest.approx(expected, abs=1e-9)
    # An undefined tool file is empty: the TCP is tool0 again.
    assert vc.select_tool(0, 7).ok
    tcp7 = vc.snapshot().groups[0].tcp
    assert tcp7 is not None
    assert tcp7.command[:3] == pytest.approx((0.0, 0.162, 0.07), abs=1e-9)


def test_tcp_speed_while_moving_matches_the_pose_change() -> None:
    vc = _cell()
    tick_until(vc, lambda: vc.snapshot().servo, "servo on")
    enter_traj_mode(vc)
    assert start_at_current(vc).ok
    target = [0.4, 0.3, 0.5, 0.0, 0.0, 0.0]
    assert send(vc, 1, point(0, 2.0, target)).ok
    for _ in range(200):  # into the middle of the move
        vc.tick()
    before = vc.snapshot().groups[0]
    vc.tick()
    after = vc.snapshot().groups[0]
    assert before.tcp is not None
    assert after.tcp is not None
    moved = np.linalg.norm(np.subtract(after.tcp.command[:3], before.tcp.command[:3]))
    per_tick_mm_s = moved * 1000.0 / (vc.cell.controller.interpolation_period_ms / 1000.0)
    assert after.tcp.command_speed_mm_s > 10.0
    assert after.tcp.command_speed_mm_s == pytest.approx(per_tick_mm_s, rel=0.02)
    assert after.tcp.feedback_speed_mm_s > 0.0


def test_increment_speed_for_an_fsu_limit() -> None:
    from pymotoros.controller.tool_point import TcpTracker

    vc = _cell()
    tracker = TcpTracker(vc.cell)
    group = vc.cell.groups[0]
    pulses = [0] * 8
    # 100 pulses of the S axis in 4 ms: the TCP turns about the S axis at radius r.
    inc = [100, 0, 0, 0, 0, 0, 0, 0]
    omega = 100 / group.axes[0].pulses_per_unit / 0.004
    radius = math.hypot(0.0, 0.162)  # folded HC10: tool0 0.162 m off the S axis
    speed = tracker.increment_speed_mm_s(0, 0, pulses, inc)
    assert speed == pytest.approx(omega * radius * 1000, rel=1e-3)
    assert tracker.increment_speed_mm_s(0, 0, pulses, [0] * 8) == 0.0
