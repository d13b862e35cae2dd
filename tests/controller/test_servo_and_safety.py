"""Servo model, E-stop, PFL, the inc-move latch, eco mode, and the operator transitions."""

from __future__ import annotations

import pytest

from pymotoros.controller import PendantMode, Pending, VirtualController, cell_from_dict
from pymotoros.controller.machine import (
    TRANSITIONS,
    EstopSource,
    Event,
    OperatorState,
    ServoPower,
)
from pymotoros.controller.servo import ServoGroup
from pymotoros.controller.signals import ECO_MODE, PFL_AVOID_JOINT, PFL_AVOIDING, PFL_STOP, SERVO_ON
from pymotoros.protocol.constants import NotReadySubcode as Nr
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, complete, point, send, tick_until
from .states import moving, ready, settle_monitor

# ------------------------------------------------------------------ servo model


def test_feedback_lags_by_the_configured_ticks_and_settles() -> None:
    servo = ServoGroup([0] * 6, period_ms=4, lag_ticks=2)
    for _ in range(10):
        servo.apply((100, 0, 0, 0, 0, 0, 0, 0))
    # constant speed: feedback = command − lag × speed
    assert servo.command[0] == 1000
    assert servo.feedback(10, powered=True)[0] == 1000 - 2 * 100
    assert servo.speed()[0] == 100 * 250  # pulses per second at 4 ms
    for k in range(3):
        servo.idle()
        assert servo.feedback(11 + k, powered=True)[0] < 1000
    servo.idle()  # 2 × lag ticks after the last increment
    assert servo.feedback(14, powered=True)[0] == 1000
    servo.idle()
    assert servo.settled()
    assert servo.speed()[0] == 0


def test_no_lag_means_feedback_is_the_command() -> None:
    servo = ServoGroup([5] * 6, period_ms=4, lag_ticks=0)
    servo.apply((7, 0, 0, 0, 0, 0, 0, 0))
    assert servo.feedback(1, powered=True)[:2] == [12, 5]


def test_noise_is_bounded_deterministic_and_only_when_powered() -> None:
    a = ServoGroup([0] * 6, period_ms=4, lag_ticks=0, noise_pulses=3, seed=7)
    b = ServoGroup([0] * 6, period_ms=4, lag_ticks=0, noise_pulses=3, seed=7)
    samples = [a.feedback(t, powered=True) for t in range(200)]
    assert samples == [b.feedback(t, powered=True) for t in range(200)]
    values = {v for s in samples for v in s}
    assert values <= set(range(-3, 4))
    assert len(values) > 3
    assert a.feedback(5, powered=False) == [0] * 8


def test_in_motion_uses_30_pulses_between_feedback_and_command() -> None:
    vc = ready()
    assert send(vc, 0, point(0, 0.0, [0.0] * 6)).ok
    # ends at speed: MotoROS adds no ramp, the command stops dead, the feedback trails
    assert send(vc, 1, point(0, 0.5, [0.2] * 6, [0.4] * 6)).ok
    tick_until(vc, vc.has_queued_motion, "queued", max_ticks=5)
    tick_until(vc, lambda: not vc.has_queued_motion(), "drained", max_ticks=500)
    assert vc.robot_status().in_motion == 1  # feedback still catching up
    tick_until(vc, lambda: vc.robot_status().in_motion == 0, "settled", max_ticks=50)


# ------------------------------------------------------------------ E-stop


def test_estop_mid_motion_reaches_a_safe_state_on_the_same_tick() -> None:
    vc = moving()
    vc.press_estop(True)
    snap = vc.snapshot()
    assert snap.estop
    assert not snap.servo
    assert vc.job_position == ()
    assert snap.alarms == ()  # E-stop raises no alarm
    before = snap.groups[0].command_pulse
    vc.tick()
    assert not vc.has_queued_motion()
    assert vc.snapshot().groups[0].command_pulse == before
    vc.run_ticks(3)
    status = vc.robot_status()
    assert (status.e_stopped, status.drives_powered, status.in_error) == (1, 0, 0)
    # recovery: release, START_TRAJ_MODE (servo on, job), start again from where it stopped
    vc.press_estop(False)
    assert command(vc, CMD.START_TRAJ_MODE).ok
    here = list(vc.snapshot().groups[0].command_rad)
    assert send(vc, 0, point(0, 0.0, here)).ok


def test_servo_on_is_refused_while_estopped() -> None:
    vc = VirtualController()
    vc.press_estop(True)
    vc.set_servo(True)
    vc.run_ticks(200)
    assert not vc.snapshot().servo
    outcome = command(vc, CMD.START_SERVOS)
    assert (outcome.result, outcome.subcode) == (R.FAILURE, 0)
    assert "E-stop" in outcome.detail


def test_servo_on_takes_the_servo_on_delay() -> None:
    vc = VirtualController()
    pending = vc.motion_ctrl(0, CMD.START_SERVOS)
    delay = vc.cell.servo.servo_on_delay_ms
    vc.run_ticks(delay // vc.period_ms - 1)
    assert vc.io.get(SERVO_ON) == 0
    assert complete(vc, pending).ok
    assert vc.io.get(SERVO_ON) == 1
    assert delay <= vc.time_ms <= delay + 50 + vc.period_ms


# ------------------------------------------------------------------ PFL


def test_pfl_event_refuses_with_5011_until_start_traj_mode() -> None:
    vc = moving()
    vc.force_io(PFL_STOP, 1)
    settle_monitor(vc)
    assert not vc.has_queued_motion()
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.PFL_ACTIVE
    vc.force_io(PFL_STOP, 0)  # the PFL sequence is over: still latched
    settle_monitor(vc)
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.PFL_ACTIVE
    here = list(vc.snapshot().groups[0].command_rad)
    o = complete(vc, vc.trajectory_point(0, point(0, 0.0, here)))
    assert (o.result, o.subcode) == (R.NOT_READY, Nr.PFL_ACTIVE)
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert send(vc, 0, point(0, 0.0, here)).ok


def test_pfl_avoidance_needs_joint_or_translation() -> None:
    vc = ready()
    vc.force_io(PFL_AVOIDING, 1)
    settle_monitor(vc)
    assert command(vc, CMD.CHECK_MOTION_READY).ok
    vc.force_io(PFL_AVOID_JOINT, 1)
    settle_monitor(vc)
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.PFL_ACTIVE


def test_pfl_signals_ignored_without_the_option() -> None:
    vc = VirtualController(cell_from_dict({"controller": {"pfl": False}}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    vc.force_io(PFL_STOP, 1)
    settle_monitor(vc)
    assert command(vc, CMD.CHECK_MOTION_READY).ok


# ------------------------------------------------------------------ inc-move error latch


def test_inc_move_error_latch_cleared_by_start_traj_mode() -> None:
    from .states import inc_move_error

    vc = inc_move_error()
    assert not vc.has_queued_motion()
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.INC_MOVE_ERROR
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert not vc.motoros.inc_move_error


# ------------------------------------------------------------------ eco mode


def test_eco_mode_wakes_on_motion() -> None:
    vc = ready()
    vc.set_eco(True)
    settle_monitor(vc)
    assert vc.io.get(ECO_MODE) == 1
    assert vc.robot_status().drives_powered == 0
    here = list(vc.snapshot().groups[0].command_rad)
    # sequence 0 in eco mode: STOP_TRAJ_MODE, START_TRAJ_MODE, then the start (v1.9.12)
    pending = vc.trajectory_point(0, point(0, 0.0, here))
    assert isinstance(pending, Pending)
    outcome = complete(vc, pending)
    assert outcome.ok, outcome.detail
    assert vc.io.get(ECO_MODE) == 0
    assert command(vc, CMD.CHECK_MOTION_READY).ok
    assert send(vc, 1, point(0, 0.5, [q + 0.05 for q in here])).ok
    tick_until(vc, lambda: not vc.has_queued_motion(), "moved")


def test_eco_mode_during_a_move_retries_then_moves() -> None:
    vc = moving()
    vc.set_eco(True)
    start = vc.snapshot().groups[0].command_pulse
    vc.run_ticks(5)
    assert vc.motoros.waiting  # IncMove retries every 50 ms while the servo wakes up
    tick_until(vc, lambda: not vc.has_queued_motion(), "drained", max_ticks=2000)
    assert vc.snapshot().groups[0].command_pulse != start
    assert not vc.motoros.inc_move_error


# ------------------------------------------------------------------ the transition table


def test_every_event_has_a_transition() -> None:
    assert set(TRANSITIONS) == set(Event)


@pytest.mark.parametrize(
    ("state", "event", "refused"),
    [
        (OperatorState(estop=frozenset(EstopSource)), Event.REQUEST_SERVO_ON, "E-stop"),
        (OperatorState(servo=ServoPower.ON, hold=True), Event.START_JOB, "HOLD"),
        (OperatorState(servo=ServoPower.ON, remote=False), Event.START_JOB, "REMOTE"),
        (OperatorState(), Event.START_JOB, "servo power is off"),
        (OperatorState(), Event.ENTER_ECO, "servo power on"),
        (OperatorState(), Event.SERVO_POWER_READY, "not requested"),
    ],
)
def test_guard_reasons(state: OperatorState, event: Event, refused: str) -> None:
    failing = [g.why for g in TRANSITIONS[event].guards if not g.holds(state)]
    assert any(refused in why for why in failing), failing


def test_start_job_guards() -> None:
    guards = {g.name for g in TRANSITIONS[Event.START_JOB].guards}
    assert guards == {
        "play",
        "remote",
        "no_estop",
        "no_alarm",
        "servo_on",
        "not_held",
        "job_not_running",
    }


def test_teach_mode_stops_the_job_and_refuses_start() -> None:
    vc = ready()
    vc.set_mode(PendantMode.TEACH)
    assert vc.job_position == ()
    vc.force_io(50053, 1)
    with pytest.raises(ValueError, match="not in PLAY mode"):
        vc.force_io(50070, 1)


def test_minor_alarm_keeps_servo_major_cuts_it() -> None:
    vc = ready()
    vc.raise_alarm(4100, 0, "minor")
    assert vc.snapshot().servo
    assert vc.job_position == ()
    vc.raise_alarm(1000, 0, "major")
    assert not vc.snapshot().servo
    assert [a.code for a in vc.alarm_history()] == [4100, 1000]
    vc.reset()
    assert vc.snapshot().alarms == ()
    assert len(vc.alarm_history()) == 2


def test_observers_get_frozen_snapshots() -> None:
    vc = VirtualController()
    seen = []
    vc.subscribe(seen.append)
    vc.set_hold(True)
    vc.set_hold(True)  # no change, no notification
    vc.set_hold(False)
    assert [s.hold for s in seen] == [True, False]
    with pytest.raises(AttributeError):
        seen[0].hold = False  # type: ignore[misc]


def _between_monitor_runs(vc: VirtualController) -> None:
    tick_until(
        vc,
        lambda: vc.motoros.next_monitor_ms > vc.time_ms + vc.period_ms,
        "a tick without a monitor run",
    )


def test_servo_off_mid_motion_reads_as_pfl_with_the_option() -> None:
    """The users' #410 case: an increment refused with no E-stop/hold/alarm/error."""
    vc = moving()
    _between_monitor_runs(vc)
    vc.set_servo(False)
    vc.tick()
    assert vc.motoros.pfl_during_move
    assert vc.motoros.inc_move_error
    vc.set_servo(True)
    vc.run_ticks(200)
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.PFL_ACTIVE
    assert command(vc, CMD.START_TRAJ_MODE).ok


def test_servo_off_mid_motion_without_pfl_latches_5012() -> None:
    vc = VirtualController(cell_from_dict({"controller": {"pfl": False}}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert send(vc, 0, point(0, 0.0, [0.0] * 6)).ok
    assert send(vc, 1, point(0, 2.0, [0.5] * 6)).ok
    vc.run_ticks(20)
    _between_monitor_runs(vc)
    vc.set_servo(False)
    vc.tick()
    assert not vc.motoros.pfl_during_move
    assert vc.motoros.inc_move_error
    assert not vc.has_queued_motion()


def test_docs_show_the_current_transition_table() -> None:
    from pathlib import Path

    from pymotoros.controller.machine import transition_table

    doc = (Path(__file__).resolve().parents[2] / "docs" / "fidelity.md").read_text("utf-8")
    block = doc.split("<!-- transition-table -->\n", 1)[1].split("\n<!-- /transition-table -->")[0]
    assert block == transition_table()


def test_fsu_speed_limit_slows_the_move_but_motoros_resends_the_pulses() -> None:
    def run(fsu: int | None) -> tuple[int, tuple[int, ...]]:
        controller: dict[str, object] = {"pfl": False}
        if fsu is not None:
            controller["fsu_speed_limit_pct"] = fsu
        vc = VirtualController(cell_from_dict({"controller": controller}))
        assert command(vc, CMD.START_TRAJ_MODE).ok
        assert send(vc, 0, point(0, 0.0, [0.0] * 6)).ok
        limit = [0.8 * v for v in vc.motoros.axes[0].max_speed[:6]]  # 80 % of max speed
        assert send(vc, 1, point(0, 1.0, limit, limit)).ok
        start = vc.time_ms
        tick_until(vc, vc.has_queued_motion, "queued", max_ticks=5)
        tick_until(
            vc,
            lambda: not vc.has_queued_motion() and not any(map(any, vc.motoros.unprocessed_pulses)),
            "every pulse executed",
        )
        assert not vc.motoros.inc_move_error
        return vc.time_ms - start, vc.snapshot().groups[0].command_pulse

    free_ms, free_end = run(None)
    slow_ms, slow_end = run(50)
    assert slow_end == free_end  # every pulse arrives in the end
    assert slow_ms > 1.4 * free_ms  # but later: the FSU let half the speed through


def test_eco_idle_timer_and_brake_sag_give_the_3011_users_meet() -> None:
    """ros-industrial/motoman#501: a start planned before eco mode fails after it."""
    cell = cell_from_dict({"controller": {"eco_idle_s": 2, "brake_sag_pulses": 200}})
    vc = VirtualController(cell)
    assert command(vc, CMD.START_TRAJ_MODE).ok
    planned = list(vc.joint_feedback(0).pos[:6])  # the client reads the state …
    tick_until(vc, lambda: vc.snapshot().servo and vc.io.get(ECO_MODE) == 1, "eco", 1000)
    assert vc.time_ms >= 2000
    settle_monitor(vc)
    assert vc.robot_status().drives_powered == 0
    # … and starts from it after eco mode: the brakes moved the axes meanwhile
    o = complete(vc, vc.trajectory_point(0, point(0, 0.0, planned)))
    assert (o.result, o.subcode) == (R.INVALID, 3011)
    assert vc.io.get(ECO_MODE) == 0  # the sequence-0 re-enable left eco mode
    fresh = list(vc.joint_feedback(0).pos[:6])
    assert send(vc, 0, point(0, 0.0, fresh)).ok


def test_no_sag_by_default() -> None:
    vc = ready()
    before = vc.snapshot().groups[0].command_pulse
    vc.press_estop(True)
    assert vc.snapshot().groups[0].command_pulse == before
