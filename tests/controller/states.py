"""Named controller states, each reached from boot the way an operator or client would."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from pymotoros.controller import CellConfig, PendantMode, VirtualController, default_cell
from pymotoros.controller.signals import PFL_STOP

from .helpers import CMD, command, complete, enter_traj_mode, point, tick_until


def settle_monitor(vc: VirtualController) -> None:
    """Let the 10 ms status monitor see the latest change."""
    vc.run_ticks(3)


def boot(cell: CellConfig | None = None) -> VirtualController:
    return VirtualController(cell)


def ready(cell: CellConfig | None = None) -> VirtualController:
    vc = VirtualController(cell)
    enter_traj_mode(vc)
    return vc


def _ready_then(change: Callable[[VirtualController], object]) -> Callable[[], VirtualController]:
    """The state reached from ``ready`` by one operator ``change``, once the monitor saw it."""

    def reach() -> VirtualController:
        vc = ready()
        change(vc)
        settle_monitor(vc)
        return vc

    return reach


estop = _ready_then(lambda vc: vc.press_estop(True))
hold = _ready_then(lambda vc: vc.set_hold(True))
teach = _ready_then(lambda vc: vc.set_mode(PendantMode.TEACH))
not_remote = _ready_then(lambda vc: vc.set_remote(False))
alarm = _ready_then(lambda vc: vc.raise_alarm(1000, 2, "major alarm for the test"))
error = _ready_then(lambda vc: vc.raise_error(2010, 0, "operator error for the test"))


def pfl() -> VirtualController:
    """A PFL stop happened during trajectory mode and is over again: the latch remains."""
    vc = ready()
    vc.force_io(PFL_STOP, 1)
    settle_monitor(vc)
    vc.force_io(PFL_STOP, 0)
    settle_monitor(vc)
    return vc


def moving(cell: CellConfig | None = None) -> VirtualController:
    """In trajectory mode with increments queued (a 2 s move under way)."""
    vc = ready(cell)
    here = list(vc.snapshot().groups[0].command_rad)
    assert complete(vc, vc.trajectory_point(0, point(0, 0.0, here))).ok
    there = [q + 0.5 for q in here]
    assert complete(vc, vc.trajectory_point(1, point(0, 2.0, there))).ok
    vc.run_ticks(20)
    assert vc.has_queued_motion()
    return vc


def inc_move_error() -> VirtualController:
    """HOLD pressed mid-motion, between two status-monitor runs: the increment call fails."""
    vc = moving()
    tick_until(
        vc,
        lambda: vc.motoros.next_monitor_ms > vc.time_ms + vc.period_ms,
        "a tick without a monitor run",
    )
    vc.set_hold(True)
    vc.tick()
    assert vc.motoros.inc_move_error
    vc.set_hold(False)
    settle_monitor(vc)
    return vc


def job_not_running() -> VirtualController:
    vc = VirtualController()
    vc.set_servo(True)
    tick_until(vc, lambda: vc.snapshot().servo, "servo on")
    settle_monitor(vc)
    return vc


def waiting_ros() -> VirtualController:
    """INIT_ROS started, still in its TIMER before it raises OT#889."""
    vc = job_not_running()
    vc.force_io(50070, 1)  # the operator starts the job
    vc.run_ticks(3)
    assert vc.job_position, "the job should be running"
    return vc


STATES: dict[str, Callable[[], VirtualController]] = {
    "boot": boot,
    "ready": ready,
    "estop": estop,
    "hold": hold,
    "teach": teach,
    "not_remote": not_remote,
    "alarm": alarm,
    "error": error,
    "pfl": pfl,
    "inc_move_error": inc_move_error,
    "job_not_running": job_not_running,
    "waiting_ros": waiting_ros,
}

__all__ = ["CMD", "STATES", "command"]


def safe_cell() -> CellConfig:
    """The default cell in fidelity safe: the motion connection's close clears the queues."""
    return dataclasses.replace(default_cell(), fidelity="safe")
