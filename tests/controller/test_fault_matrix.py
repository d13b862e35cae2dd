"""The fault matrix (issue 13, item 8): every operator fault in every phase of a
trajectory, with the outcome of the reference (§3.6 queue clearing, §4.2 the NOT_READY
subcode CHECK_MOTION_READY answers), and the recovery an operator and a client perform.

Phases: ``idle`` (booted, trajectory mode never started), ``motion-ready`` (trajectory
mode on, nothing queued), ``streaming`` (increments queued and a point pending) and
``last segment`` (every point accepted, the queue draining the last segment).

PFL/FSU events (issue 9, in progress) join :data:`FAULTS` as entries of the same shape
once the controller has them: an ``inject``, the subcode, and a ``recover``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import pytest

from pymotoros.controller import PendantMode, VirtualController
from pymotoros.protocol.constants import NotReadySubcode as Nr

from .helpers import CMD, command, current_pos, point, send, start_at_current, tick_until
from .states import boot, moving, ready, settle_monitor

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


def last_segment() -> VirtualController:
    """Every point accepted; the queue holds the tail of the last segment."""
    vc = moving()
    interp = vc.motoros.interpolators[0]
    tick_until(vc, lambda: not interp.pending, "the last segment fully queued")
    assert vc.has_queued_motion()
    return vc


PHASES: dict[str, Callable[[], VirtualController]] = {
    "idle": boot,
    "motion-ready": ready,
    "streaming": moving,
    "last segment": last_segment,
}


@pytest.mark.parametrize("phase", list(PHASES))
@pytest.mark.parametrize("fault", list(FAULTS))
def test_fault_in_phase(fault: str, phase: str) -> None:
    f = FAULTS[fault]
    vc = PHASES[phase]()
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
    started = command(vc, CMD.START_TRAJ_MODE)
    assert started.ok, (fault, phase, started)
    assert start_at_current(vc).ok
    target = current_pos(vc)
    target[0] += RECOVERY_MOVE_RAD
    assert send(vc, 1, point(0, 0.5, target)).ok
    finish(vc)
    assert current_pos(vc)[0] == pytest.approx(target[0], abs=1e-4)


@pytest.mark.parametrize("phase", list(PHASES))
def test_eco_mode_in_phase(phase: str) -> None:
    """Eco mode saves servo power but does not change motion-ready (§4.1), so it clears
    nothing: the queue is kept, and once the drives are back the move completes; then a
    new trajectory runs."""
    vc = PHASES[phase]()
    queued = vc.has_queued_motion()
    vc.set_eco(True)
    settle_monitor(vc)
    assert vc.has_queued_motion() == queued, phase
    if phase != "idle":
        assert command(vc, CMD.CHECK_MOTION_READY).ok, phase
    vc.set_eco(False)
    settle_monitor(vc)
    finish(vc)
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert start_at_current(vc).ok
    target = current_pos(vc)
    target[0] += RECOVERY_MOVE_RAD
    assert send(vc, 1, point(0, 0.5, target)).ok
    finish(vc)
    assert current_pos(vc)[0] == pytest.approx(target[0], abs=1e-4)
