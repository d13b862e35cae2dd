"""The fault matrix (issue 13, item 8): every operator fault in every phase of a
trajectory, with the outcome of the reference (§3.6 queue clearing, §4.2 the NOT_READY
subcode CHECK_MOTION_READY answers), and the recovery an operator and a client perform.

Phases: ``idle`` (booted, trajectory mode never started), ``motion-ready`` (trajectory
mode on, nothing queued), ``streaming`` (increments queued and a point pending) and
``last segment`` (every point accepted, the queue draining the last segment).

The safety unit's events have their own rows below, because their outcome depends on
the phase in ways the operator faults' does not: a PFL stop signal (81702 on, then
off: the monitor latches "PFL during ROS move", §3.6/§4.1) in every phase; a PFL
contact or clamping (the twin's safety unit detects one only while the robot moves:
refused, with nothing changed, while it stands); an FSU speed limit switched on
(no signal to MotoROS, nothing cleared: the move slows, MotoROS 1.9.12 resends the
clipped pulses and it still ends at its target, §5.6 step 3 and seed 003's
"FSU Interaction").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import pytest

from pymotoros.controller import CellConfig, PendantMode, VirtualController, signals
from pymotoros.protocol.constants import NotReadySubcode as Nr
from pymotoros.protocol.constants import ResultCode

from .helpers import CMD, command, current_pos, point, send, start_at_current, tick_until
from .states import boot, moving, ready, safe_cell, settle_monitor

Act = Callable[[VirtualController], None]

RECOVERY_MOVE_RAD = 0.05
"""The small move of joint 1 that proves motion works again after recovery."""


@dataclass(frozen=True)
class Fault:
    inject: Act
    subcode: Nr | None
    """What CHECK_MOTION_READY answers once the monitor has seen the fault (None: the
    client cannot ask, e.g. its connection is gone)."""
    recover: Act
    """What the operator (pendant) or the client's connection does before the client
    runs START_TRAJ_MODE again."""
    clears: bool = True
    """The fault clears the queues (§3.6)."""


def _nothing(vc: VirtualController) -> None:
    del vc


FAULTS: dict[str, Fault] = {
    "E-stop": Fault(lambda vc: vc.press_estop(True), Nr.ESTOP, lambda vc: vc.press_estop(False)),
    "alarm": Fault(lambda vc: vc.raise_alarm(4100, 0, "minor alarm"), Nr.ALARM, _nothing),
    "hold": Fault(lambda vc: vc.set_hold(True), Nr.HOLD, lambda vc: vc.set_hold(False)),
    "TEACH": Fault(
        lambda vc: vc.set_mode(PendantMode.TEACH),
        Nr.NOT_PLAY,
        lambda vc: vc.set_mode(PendantMode.PLAY),
    ),
    "remote off": Fault(
        lambda vc: vc.set_remote(False), Nr.NOT_REMOTE, lambda vc: vc.set_remote(True)
    ),
    "servo off": Fault(lambda vc: vc.set_servo(False), Nr.SERVO_OFF, _nothing),
    "disconnect": Fault(
        lambda vc: vc.motion_disconnected(), None, lambda vc: vc.motion_connected()
    ),
    # issue 9 adds "PFL stop" / FSU events here.
}


def idle_again(vc: VirtualController) -> bool:
    return not (vc.motoros.interpolators[0].pending or vc.has_queued_motion())


def finish(vc: VirtualController) -> None:
    """Tick until the move is queued, executed and the queue empty (bounded)."""
    tick_until(vc, lambda: idle_again(vc), "the move done", 5000)


def last_segment(cell: CellConfig | None = None) -> VirtualController:
    """Every point accepted; the queue holds the tail of the last segment."""
    vc = moving(cell)
    interp = vc.motoros.interpolators[0]
    tick_until(vc, lambda: not interp.pending, "the last segment fully queued")
    assert vc.has_queued_motion()
    return vc


PHASES: dict[str, Callable[[CellConfig | None], VirtualController]] = {
    "idle": boot,
    "motion-ready": ready,
    "streaming": moving,
    "last segment": last_segment,
}


@pytest.mark.parametrize("phase", list(PHASES))
@pytest.mark.parametrize("fault", list(FAULTS))
def test_fault_in_phase(fault: str, phase: str) -> None:
    f = FAULTS[fault]
    # A disconnect clears the queues only in fidelity safe; exact keeps them, as MotoROS
    # does (tests/controller/test_queue_clear.py::..._keeps_the_queue_in_exact).
    vc = PHASES[phase](safe_cell() if fault == "disconnect" else None)
    f.inject(vc)
    settle_monitor(vc)
    # Outcome: the queues are cleared, nothing pending, the robot stands.
    assert not vc.has_queued_motion(), (fault, phase)
    assert not vc.motoros.interpolators[0].pending, (fault, phase)
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == 0
    if f.subcode is not None:
        ready_now = command(vc, CMD.CHECK_MOTION_READY)
        assert not ready_now.ok, (fault, phase)
        if phase != "idle":  # idle: the job never ran, so NOT_STARTED may come first
            assert ready_now.subcode == f.subcode, (fault, phase, ready_now)
    still = vc.snapshot().groups[0].command_pulse
    vc.run_ticks(50)
    assert vc.snapshot().groups[0].command_pulse == still, (fault, phase)
    # Recovery: the operator undoes the fault, the client restarts trajectory mode and
    # a new trajectory from where the robot stands runs to its end.
    f.recover(vc)
    settle_monitor(vc)
    recovery_move(vc)


@pytest.mark.parametrize("phase", list(PHASES))
def test_eco_mode_in_phase(phase: str) -> None:
    """Eco mode saves servo power but does not change motion-ready (§4.1), so it clears
    nothing: the queue is kept, and once the drives are back the move completes; then a
    new trajectory runs."""
    vc = PHASES[phase](None)
    queued = vc.has_queued_motion()
    vc.set_eco(True)
    settle_monitor(vc)
    assert vc.has_queued_motion() == queued, phase
    if phase != "idle":
        assert command(vc, CMD.CHECK_MOTION_READY).ok, phase
    vc.set_eco(False)
    settle_monitor(vc)
    finish(vc)
    recovery_move(vc)


def recovery_move(vc: VirtualController) -> None:
    """START_TRAJ_MODE, a start point where the robot stands and a small move of joint
    1, run to its end: motion works again."""
    started = command(vc, CMD.START_TRAJ_MODE)
    assert started.ok, started
    assert start_at_current(vc).ok
    target = current_pos(vc)
    target[0] += RECOVERY_MOVE_RAD
    assert send(vc, 1, point(0, 0.5, target)).ok
    finish(vc)
    assert current_pos(vc)[0] == pytest.approx(target[0], abs=1e-4)


def assert_stands_and_cleared(vc: VirtualController, what: tuple[str, str]) -> None:
    assert not vc.has_queued_motion(), what
    assert not vc.motoros.interpolators[0].pending, what
    still = vc.snapshot().groups[0].command_pulse
    vc.run_ticks(50)
    assert vc.snapshot().groups[0].command_pulse == still, what


def pfl_signals_clear(vc: VirtualController) -> None:
    tick_until(
        vc,
        lambda: not (vc.io.get(signals.PFL_STOP) or vc.io.get(signals.PFL_ESCAPE)),
        "the PFL signals clear",
        2000,
    )


@pytest.mark.parametrize("phase", list(PHASES))
def test_pfl_stop_signal_in_phase(phase: str) -> None:
    """PFL stop (81702) on, then off, as the safety unit signals it: in every phase the
    monitor clears the queues and latches "PFL during ROS move" (5011 while trajectory
    mode is on), which only START_TRAJ_MODE clears."""
    vc = PHASES[phase](None)
    vc.force_io(signals.PFL_STOP, 1)
    settle_monitor(vc)
    assert_stands_and_cleared(vc, ("PFL stop", phase))
    vc.force_io(signals.PFL_STOP, 0)
    settle_monitor(vc)
    check = command(vc, CMD.CHECK_MOTION_READY)
    assert not check.ok, phase
    if phase != "idle":  # idle: the job never ran, so NOT_STARTED may come first
        assert check.subcode == Nr.PFL_ACTIVE, (phase, check)
        refused = send(vc, 2, point(0, 0.0, current_pos(vc)))
        assert (refused.result, refused.subcode) == (ResultCode.NOT_READY, Nr.PFL_ACTIVE)
    recovery_move(vc)
    assert not vc.motoros.pfl_during_move


PFL_EVENTS = ["contact", "clamping"]
MOVING_PHASES = ("streaming", "last segment")


@pytest.mark.parametrize("phase", list(PHASES))
@pytest.mark.parametrize("event", PFL_EVENTS)
def test_pfl_event_in_phase(event: str, phase: str) -> None:
    vc = PHASES[phase](None)
    if phase not in MOVING_PHASES:
        # The robot stands: no contact to detect. Refused, saying why; nothing changes.
        queued = vc.has_queued_motion()
        with pytest.raises(ValueError, match="stands still"):
            vc.pfl_event(event)
        settle_monitor(vc)
        assert vc.has_queued_motion() == queued
        assert not vc.io.get(signals.PFL_STOP)
        assert not vc.motoros.pfl_during_move
        if phase == "motion-ready":
            assert command(vc, CMD.CHECK_MOTION_READY).ok
        recovery_move(vc)
        return
    vc.pfl_event(event)
    assert vc.io.get(signals.PFL_STOP) == 1
    settle_monitor(vc)
    assert not vc.has_queued_motion(), (event, phase)
    assert not vc.motoros.interpolators[0].pending, (event, phase)
    check = command(vc, CMD.CHECK_MOTION_READY)
    assert (check.ok, check.subcode) == (False, Nr.PFL_ACTIVE), (event, phase, check)
    at_contact = current_pos(vc)[0]
    # Recovery: the safety unit ends its sequence (a clamping retreats first), the
    # latch stays until the client restarts trajectory mode.
    pfl_signals_clear(vc)
    if event == "clamping":
        assert current_pos(vc)[0] < at_contact, phase  # moved back along joint 1's path
    assert_stands_and_cleared(vc, (event, phase))
    still = command(vc, CMD.CHECK_MOTION_READY)
    assert (still.ok, still.subcode) == (False, Nr.PFL_ACTIVE), (event, phase, still)
    recovery_move(vc)
    assert not vc.motoros.pfl_during_move


FSU_LIMITS: dict[str, dict[str, float]] = {
    "joint speed 5 %": {"joint_speed_pct": 5},
    "TCP speed 50 mm/s": {"tcp_speed_mm_s": 50.0},
}
"""FSU speed limits switched on at run time (the TCP limit uses the HC10's kinematics)."""

MOVE_TARGET_OFFSET_RAD = 0.5
"""Where :func:`states.moving` sends every joint: 0.5 rad from the boot pose, in 2 s."""


FSU_SLOWER = 1.2
"""A limited move takes at least this much longer than the same move unlimited: both
limits are below what :func:`states.moving`'s move needs (every joint 0.5 rad in 2 s,
peaking near 0.4 rad/s: ~18 % of the HC10's slowest axis (2.27 rad/s), well over 50 mm/s at the
flange)."""


def ticks_to_finish(vc: VirtualController) -> int:
    """Controller ms until the queue is empty and every clipped pulse was resent."""
    began = vc.time_ms
    finish(vc)
    tick_until(vc, lambda: not any(map(any, vc.motoros.unprocessed_pulses)), "pulses resent")
    return vc.time_ms - began


@pytest.mark.parametrize("phase", list(PHASES))
@pytest.mark.parametrize("limit", list(FSU_LIMITS))
def test_fsu_limit_in_phase(limit: str, phase: str) -> None:
    """Nothing is cleared and nothing refused: the FSU clips increments without telling
    MotoROS; its compensation resends what was clipped, so the move (if any) still ends
    exactly at its target, later. Switching the limit off restores full speed."""
    vc = PHASES[phase](None)
    queued = vc.has_queued_motion()
    vc.set_fsu(**FSU_LIMITS[limit])  # type: ignore[arg-type]
    settle_monitor(vc)
    assert vc.has_queued_motion() == queued, (limit, phase)
    if phase != "idle":
        assert command(vc, CMD.CHECK_MOTION_READY).ok, (limit, phase)
    limited_ms = ticks_to_finish(vc)
    assert not vc.motoros.inc_move_error, (limit, phase)
    if phase in MOVING_PHASES:
        boot_pose = VirtualController().snapshot().groups[0].command_rad
        target = [q + MOVE_TARGET_OFFSET_RAD for q in boot_pose]
        assert current_pos(vc)[:6] == pytest.approx(target[:6], abs=1e-4), (limit, phase)
        free = PHASES[phase](None)
        assert limited_ms > FSU_SLOWER * ticks_to_finish(free), (limit, phase)
    vc.set_fsu(off=True)
    recovery_move(vc)
