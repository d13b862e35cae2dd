"""The whole life cycle in virtual time, in a plain loop, with no event loop."""

from __future__ import annotations

import math
from functools import partial

from pymotoros.controller import Pending, VirtualController
from pymotoros.controller.signals import OPERATING, ROS_DONE, ROS_READY
from pymotoros.protocol.constants import NotReadySubcode, ResultCode

from .helpers import CMD, command, complete, point, resend_while_busy, tick_until


def test_boot_start_stream_stop() -> None:
    vc = VirtualController()
    assert vc.time_ms == 0

    # boot state: PLAY, REMOTE, servo off, nothing pressed, INIT_ROS loaded not running
    snap = vc.snapshot()
    assert (snap.mode.value, snap.remote, snap.servo, snap.estop, snap.hold) == (
        "play",
        True,
        False,
        False,
        False,
    )
    assert snap.alarms == ()
    assert not snap.motion_ready
    assert vc.job_position == ()
    ready = command(vc, CMD.CHECK_MOTION_READY)
    assert (ready.result, ready.subcode) == (ResultCode.FALSE, NotReadySubcode.SERVO_OFF)

    # START_TRAJ_MODE takes controller time: servo on, INIT_ROS, OT#889
    pending = vc.motion_ctrl(0, CMD.START_TRAJ_MODE)
    assert isinstance(pending, Pending), "START_TRAJ_MODE takes controller time"
    started_at = vc.time_ms
    outcome = complete(vc, pending)
    assert outcome.ok, outcome
    assert vc.time_ms - started_at >= vc.cell.servo.servo_on_delay_ms
    assert vc.io.get(ROS_READY) == 1
    assert vc.io.get(OPERATING) == 1
    assert command(vc, CMD.CHECK_MOTION_READY).ok
    assert vc.robot_status().motion_possible == 1

    # a 40-point trajectory on all six axes, 50 ms apart, resending on BUSY
    target = [0.3, -0.2, 0.4, 0.5, -0.6, 0.7]
    n = 40
    busy = 0
    for seq in range(n + 1):
        s = seq / n
        shape = 10 * s**3 - 15 * s**4 + 6 * s**5  # smooth start and stop
        dshape = (30 * s**2 - 60 * s**3 + 30 * s**4) / (n * 0.05)
        p = point(0, seq * 0.05, [t * shape for t in target], [t * dshape for t in target])
        result, retries = resend_while_busy(vc, partial(vc.trajectory_point, seq, p), 500)
        busy += retries
        assert result.ok, (seq, result)
    assert busy > 0, "the stream should have met BUSY at least once"
    assert vc.robot_status().in_motion == 1

    tick_until(vc, lambda: not vc.has_queued_motion(), "queue drained")
    group = vc.snapshot().groups[0]
    axes_ppr = [a.pulses_per_unit for a in vc.cell.groups[0].axes]
    for cmd, want, ppr in zip(group.command_rad, target, axes_ppr, strict=True):
        assert math.isclose(cmd, want, abs_tol=1.0 / ppr), (cmd, want)
    # feedback lags, then settles onto the command
    tick_until(vc, lambda: vc.robot_status().in_motion == 0, "in_motion cleared")
    vc.run_ticks(2 * vc.cell.servo.lag_ticks + 1)
    settled = vc.snapshot().groups[0]
    assert settled.feedback_rad == settled.command_rad
    fb = vc.joint_feedback(0)
    assert fb.valid_fields == 6
    assert fb.vel[:6] == (0.0,) * 6
    assert fb.pos[:6] == settled.feedback_rad

    # STOP_TRAJ_MODE releases the job: OT#890, the job ends, not ready any more
    assert command(vc, CMD.STOP_TRAJ_MODE).ok
    assert vc.io.get(ROS_DONE) == 1
    tick_until(vc, lambda: vc.job_position == (), "INIT_ROS ended")
    vc.run_ticks(3)  # one status-monitor period
    assert vc.io.get(OPERATING) == 0
    not_ready = command(vc, CMD.CHECK_MOTION_READY)
    assert (not_ready.result, not_ready.subcode) == (ResultCode.FALSE, NotReadySubcode.NOT_STARTED)
    # and trajectory mode can be entered again
    assert command(vc, CMD.START_TRAJ_MODE).ok


def test_feedback_differs_while_moving() -> None:
    vc = VirtualController()
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert complete(vc, vc.trajectory_point(0, point(0, 0.0, [0.0] * 6))).ok
    assert complete(vc, vc.trajectory_point(1, point(0, 1.0, [1.0] * 6, [0.0] * 6))).ok
    vc.run_ticks(120)  # mid-segment
    g = vc.snapshot().groups[0]
    assert all(fb < cmd for fb, cmd in zip(g.feedback_rad, g.command_rad, strict=True))
    assert vc.robot_status().in_motion == 1
    assert any(v > 0 for v in vc.joint_feedback(0).vel[:6])


def test_same_seed_same_run() -> None:
    def run(seed: int) -> tuple[float, ...]:
        from pymotoros.controller import cell_from_dict

        cell = cell_from_dict({"controller": {"feedback_noise_pulses": 3}})
        vc = VirtualController(cell, seed=seed)
        assert command(vc, CMD.START_TRAJ_MODE).ok
        vc.run_ticks(10)
        return vc.joint_feedback(0).pos

    assert run(1) == run(1)
    assert run(1) != run(2)
