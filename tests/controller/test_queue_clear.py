"""Every queue-clearing trigger of reference §3.6, and what does not clear."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pymotoros.controller import PendantMode, VirtualController
from pymotoros.controller.lint import ResumedMotion
from pymotoros.controller.signals import PFL_STOP, ROS_READY
from pymotoros.motion.constants import QUEUE_SIZE

from .helpers import CMD, command
from .states import moving, safe_cell, settle_monitor

TRIGGERS: dict[str, Callable[[VirtualController], None]] = {
    "alarm": lambda vc: vc.raise_alarm(4100, 0, "minor alarm"),
    "E-stop": lambda vc: vc.press_estop(True),
    "hold": lambda vc: vc.set_hold(True),
    "TEACH": lambda vc: vc.set_mode(PendantMode.TEACH),
    "remote off": lambda vc: vc.set_remote(False),
    "servo off": lambda vc: vc.set_servo(False),
    "job stopped": lambda vc: vc.force_io(50070, 0),
    "OT#889 falls": lambda vc: vc.force_io(ROS_READY, 0),
    "PFL stop": lambda vc: vc.force_io(PFL_STOP, 1),
    "STOP_MOTION": lambda vc: command(vc, CMD.STOP_MOTION) and None,
    "STOP_SERVOS": lambda vc: command(vc, CMD.STOP_SERVOS) and None,
}


@pytest.mark.parametrize("trigger", list(TRIGGERS))
def test_trigger_clears_every_queue(trigger: str) -> None:
    vc = moving()
    interp = vc.motoros.interpolators[0]
    assert vc.has_queued_motion()
    assert interp.pending
    TRIGGERS[trigger](vc)
    settle_monitor(vc)
    assert not vc.has_queued_motion(), trigger
    assert not interp.pending, trigger
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == 0


def test_motion_connection_closed_clears_every_queue_in_safe() -> None:
    vc = moving(safe_cell())
    interp = vc.motoros.interpolators[0]
    assert interp.pending
    queued = command(vc, CMD.CHECK_QUEUE_CNT).subcode
    assert queued > 0
    vc.motion_disconnected()
    settle_monitor(vc)
    assert not vc.has_queued_motion()
    assert not interp.pending
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == 0
    # what a robot would have kept and resumed: the client lint's reconnect-resumed-motion
    resumed = vc.motion_connected()
    assert resumed is not None
    assert resumed.cleared_s is not None
    assert resumed.cleared_s == pytest.approx(queued * vc.period_ms / 1000)
    assert vc.motion_connected() is None  # the next connection: nothing left to resume


@pytest.mark.parametrize(
    ("fidelity", "trigger"),
    [("exact", "alarm"), ("safe", "alarm"), ("safe", "servo off"), ("safe", None)],
)
def test_a_clear_while_disconnected_leaves_nothing_to_resume(
    fidelity: str, trigger: str | None
) -> None:
    """Between the close and the next connection a clearing trigger empties the robot's
    kept queues (exact); safe, which cleared them at the close, forgets what a robot would
    have resumed for the same triggers. No trigger (safe): the next connection would resume."""
    vc = moving(safe_cell() if fidelity == "safe" else None)
    vc.motion_disconnected()
    settle_monitor(vc)
    if trigger is not None:
        TRIGGERS[trigger](vc)
        settle_monitor(vc)
    assert (vc.motion_connected() is None) is (trigger is not None)


def test_motion_connection_closed_keeps_the_queue_in_exact() -> None:
    """§2.2: the tasks are deleted (nothing executes, the pending point is dropped), the
    queue survives, and the next motion connection resumes it."""
    vc = moving()
    interp = vc.motoros.interpolators[0]
    assert interp.pending
    vc.motion_disconnected()
    settle_monitor(vc)
    queued = command(vc, CMD.CHECK_QUEUE_CNT).subcode
    assert queued > 0
    assert not interp.pending
    still = vc.snapshot().groups[0].command_pulse
    vc.run_ticks(50)
    assert vc.snapshot().groups[0].command_pulse == still  # nobody executes the queue
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == queued
    assert vc.motion_connected() == ResumedMotion()  # the next connection resumes it
    vc.run_ticks(queued + 10)
    assert vc.snapshot().groups[0].command_pulse != still
    assert not vc.has_queued_motion()
    assert vc.motion_connected() is None  # nothing left to resume


@pytest.mark.parametrize("fidelity", ["exact", "safe"])
def test_a_clear_while_a_segment_waits_for_room_queues_nothing_after(fidelity: str) -> None:
    """docs/fidelity.md §1, the race of §3.6 (safe in both settings): the 2 s segment
    has 500 steps, the queue holds 200 and the next step waits for room; after the
    STOP_MOTION nothing more is queued and the pending point is gone."""
    vc = moving(safe_cell() if fidelity == "safe" else None)
    assert vc.cell.fidelity == fidelity
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == QUEUE_SIZE  # full: a step waits
    assert command(vc, CMD.STOP_MOTION).ok
    vc.run_ticks(50)
    assert not vc.has_queued_motion()
    assert not vc.motoros.interpolators[0].pending


def test_operator_error_does_not_clear() -> None:
    vc = moving()
    vc.raise_error(2010, 0, "error")
    settle_monitor(vc)
    assert vc.has_queued_motion()


def test_release_of_estop_does_not_resume() -> None:
    vc = moving()
    vc.press_estop(True)
    settle_monitor(vc)
    vc.press_estop(False)
    settle_monitor(vc)
    before = vc.snapshot().groups[0].command_pulse
    vc.run_ticks(50)
    assert vc.snapshot().groups[0].command_pulse == before
    assert not command(vc, CMD.CHECK_MOTION_READY).ok


def test_stop_traj_mode_refused_while_queued() -> None:
    vc = moving()
    outcome = command(vc, CMD.STOP_TRAJ_MODE)
    assert (outcome.result, outcome.subcode) == (2, 0)
    assert "queued" in outcome.detail
    assert vc.has_queued_motion()


def test_start_traj_mode_when_ready_keeps_the_queue() -> None:
    """Already ready: START_TRAJ_MODE answers at once and touches nothing (§3.2 step 2)."""
    vc = moving()
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert vc.has_queued_motion()
