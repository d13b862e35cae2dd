"""Multi-group cells: JOINT_TRAJ_PT_FULL_EX streaming, 7-axis order, DX100 slaves."""

from __future__ import annotations

import math
from functools import partial

from pymotoros.controller import PointData, VirtualController, cell_from_dict, default_cell
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, complete, point, resend_while_busy, tick_until


def stream_ex(vc: VirtualController, points: list[list[PointData]]) -> int:
    busy = 0
    for seq, pts in enumerate(points):
        o, retries = resend_while_busy(vc, partial(vc.trajectory_point_ex, seq, pts))
        busy += retries
        assert o.ok, (seq, o)
        assert o.group_no == pts[-1].group_no
    return busy


def test_sda10f_streams_all_four_groups() -> None:
    vc = VirtualController(default_cell("fs100", "sda10f"))
    assert vc.num_groups == 4
    assert command(vc, CMD.START_TRAJ_MODE).ok
    groups = vc.cell.groups
    targets = [
        [0.1 * (g + 1) * (-1) ** i for i in range(len(m.axes))] for g, m in enumerate(groups)
    ]
    n = 20
    trajectory = []
    for k in range(n + 1):
        s = k / n
        shape = 10 * s**3 - 15 * s**4 + 6 * s**5
        trajectory.append(
            [point(g, k * 0.1, [t * shape for t in targets[g]]) for g in range(len(groups))]
        )
    assert stream_ex(vc, trajectory) > 0
    tick_until(vc, lambda: not vc.has_queued_motion(), "drained")
    snap = vc.snapshot()
    for g, group in enumerate(snap.groups):
        assert group.name == groups[g].name
        for got, want, axis in zip(group.command_rad, targets[g], groups[g].axes, strict=True):
            assert math.isclose(got, want, abs_tol=1.0 / axis.pulses_per_unit), (g, got, want)
    # the 7th joint in ROS order (E, index 2) is the 7th controller slot
    r1 = vc.motoros.axes[0]
    assert r1.ros_to_slot[2] == 6
    vc.run_ticks(2 * vc.cell.servo.lag_ticks + 1)
    assert vc.robot_status().in_motion == 0
    for g in range(4):
        n = len(groups[g].axes)
        assert vc.joint_feedback(g).pos[:n] == vc.snapshot().groups[g].command_rad


def test_dx100_two_arms_move_only_with_both_skill_flags() -> None:
    vc = VirtualController(
        cell_from_dict(
            {"controller": {"model": "dx100"}, "groups": [{"robot": "mh5"}, {"robot": "mh5"}]}
        )
    )
    assert command(vc, CMD.START_TRAJ_MODE).ok
    z = [0.0] * 6
    assert complete(vc, vc.trajectory_point_ex(0, [point(0, 0.0, z), point(1, 0.0, z)])).ok
    vc.motoros.on_skill(2, "ROS-STOP")  # slave 2's flag drops: not ready, 5010
    o = complete(vc, vc.trajectory_point_ex(1, [point(0, 0.5, z), point(1, 0.5, z)]))
    assert (o.result, o.subcode) == (R.NOT_READY, 5010)
    vc.motoros.on_skill(2, "ROS-START")
    o = complete(vc, vc.trajectory_point_ex(1, [point(0, 0.5, [0.1] * 6), point(1, 0.5, z)]))
    assert o.ok
    tick_until(vc, lambda: not vc.has_queued_motion() and vc.time_ms > 1000, "moved")
    assert vc.snapshot().groups[0].command_rad[0] > 0.09
