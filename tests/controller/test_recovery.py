"""Stops and recoveries a client goes through (users-and-anchors §1 items 1 and 17)."""

from __future__ import annotations

from pymotoros.controller import PendantMode, VirtualController
from pymotoros.protocol.constants import InvalidSubcode as Inv
from pymotoros.protocol.constants import NotReadySubcode as Nr
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, complete, current_pos, point, send, tick_until
from .states import moving, settle_monitor


def test_stop_motion_mid_move_then_restart_from_where_it_stopped() -> None:
    vc = moving()
    assert command(vc, CMD.STOP_MOTION).ok
    stopped = vc.snapshot().groups[0].command_pulse
    vc.run_ticks(20)
    assert vc.snapshot().groups[0].command_pulse == stopped  # no ramp, no resume
    assert command(vc, CMD.CHECK_MOTION_READY).ok  # still in trajectory mode
    # the old trajectory's next point is not a start: sequence 0 must come first, at the
    # commanded position (not the feedback, which still lags a little)
    old_start = complete(vc, vc.trajectory_point(0, point(0, 0.0, [0.0] * 6)))
    assert (old_start.result, old_start.subcode) == (R.INVALID, Inv.DATA_START_POS)
    here = current_pos(vc)
    assert send(vc, 0, point(0, 0.0, here)).ok
    assert send(vc, 1, point(0, 0.5, [q - 0.1 for q in here])).ok
    tick_until(vc, vc.has_queued_motion, "queued", max_ticks=5)
    tick_until(vc, lambda: not vc.has_queued_motion(), "drained")


def test_start_with_the_feedback_while_it_lags_can_fail_3011() -> None:
    """The classic mistake: starting from the feedback right after a fast move."""
    vc = VirtualController()
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert send(vc, 0, point(0, 0.0, [0.0] * 6)).ok
    assert send(vc, 1, point(0, 0.3, [0.3] * 6, [1.0] * 6)).ok  # ends at speed
    tick_until(vc, vc.has_queued_motion, "queued", max_ticks=5)
    tick_until(vc, lambda: not vc.has_queued_motion(), "drained")
    feedback = list(vc.joint_feedback(0).pos[:6])
    o = complete(vc, vc.trajectory_point(0, point(0, 0.0, feedback)))
    assert (o.result, o.subcode) == (R.INVALID, Inv.DATA_START_POS)
    # waiting for in_motion to clear, as Yaskawa advises, makes the feedback usable
    tick_until(vc, lambda: vc.robot_status().in_motion == 0, "settled", max_ticks=50)
    vc.run_ticks(2 * vc.cell.servo.lag_ticks)
    assert send(vc, 0, point(0, 0.0, list(vc.joint_feedback(0).pos[:6]))).ok


def test_hold_then_resume_needs_start_traj_mode() -> None:
    vc = moving()
    # press HOLD just before a status-monitor run: the monitor clears the queues before
    # IncMove tries again (pressed between runs, the refused increment latches 5012)
    tick_until(vc, lambda: vc.motoros.next_monitor_ms <= vc.time_ms + vc.period_ms, "monitor next")
    vc.set_hold(True)
    settle_monitor(vc)
    assert not vc.motoros.inc_move_error
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.HOLD
    vc.set_hold(False)
    settle_monitor(vc)
    # the job stopped: it must be started again (hold is sticky until then)
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.NOT_STARTED
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert send(vc, 0, point(0, 0.0, current_pos(vc))).ok


def test_teach_and_back() -> None:
    vc = moving()
    vc.set_mode(PendantMode.TEACH)
    o = command(vc, CMD.START_TRAJ_MODE)
    assert (o.result, o.subcode) == (R.NOT_READY, Nr.NOT_PLAY)
    vc.set_mode(PendantMode.PLAY)
    assert command(vc, CMD.START_TRAJ_MODE).ok


def test_remote_off_and_back_keeps_the_job() -> None:
    vc = moving()
    vc.set_remote(False)
    settle_monitor(vc)
    assert not vc.has_queued_motion()
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.NOT_REMOTE
    vc.set_remote(True)
    settle_monitor(vc)
    # INIT_ROS never stopped and OT#889 stayed on: ready again without START_TRAJ_MODE
    assert command(vc, CMD.CHECK_MOTION_READY).ok


def test_alarm_recovery_through_start_traj_mode() -> None:
    vc = moving()
    vc.raise_alarm(1000, 3, "major")
    settle_monitor(vc)
    status = vc.robot_status()
    assert (status.in_error, status.error_code, status.drives_powered) == (1, 1000, 0)
    assert command(vc, CMD.START_TRAJ_MODE).ok  # resets the alarm, servo on, INIT_ROS
    settle_monitor(vc)
    assert vc.robot_status().error_code == 0
    assert vc.snapshot().alarms == ()


def test_reset_alarm_command() -> None:
    vc = VirtualController()
    vc.raise_alarm(4100, 0, "minor")
    vc.raise_error(2010, 0, "error")
    assert command(vc, CMD.RESET_ALARM).ok
    snap = vc.snapshot()
    assert snap.alarms == ()
    assert snap.errors == ()
