"""MotoROS 1.9.12's logic on the virtual controller (reference §2–§6): the map, and a view.

What the MotoPlus application does is split as the real MotoROS splits it:

- :mod:`~pymotoros.controller.readiness`: whether motion is possible, composed of the
  flags of ``Controller.h`` (:mod:`~pymotoros.controller.ready_flags`), the 10 ms
  status monitor and its queue-clearing edges (:mod:`~pymotoros.controller.status_monitor`)
  and the NOT_READY subcode order (:mod:`~pymotoros.controller.not_ready`);
- :mod:`~pymotoros.controller.commands`: every MOTO_MOTION_CTRL command, as a process
  (with :mod:`~pymotoros.controller.stop_motion` and :mod:`~pymotoros.controller.polling`);
- :mod:`~pymotoros.controller.trajectory`: the validation and acceptance of trajectory
  points, SELECT_TOOL, GET_DH_PARAMETERS;
- :mod:`~pymotoros.controller.incmove_task`: the IncMove task's send and failure paths
  and the AddToIncQueue tasks;
- :mod:`~pymotoros.controller.connections` and :mod:`~pymotoros.controller.skillsnd`:
  the connection feedback outputs OT#891..894 and the DX100 SKILLSND listeners.

They drive the rest of the controller only through what MotoPlus offers MotoROS: IO
reads and writes, servo on/off, alarm reset, error cancel, job start, and the
incremental-move call. :class:`~pymotoros.controller.controller.VirtualController`
composes them; :class:`MotoRos` is the read-through view of their state it offers
tests and the pendant.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymotoros.controller.incmove_task import IncMoveTask
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.skillsnd import SkillListeners
from pymotoros.controller.trajectory import TrajectoryPoints
from pymotoros.motion import GroupAxes, GroupInterpolator


@dataclass(eq=False, repr=False)
class MotoRos:
    """MotoROS's flags and per-group state, read (and for tests, changed) through one object.

    Every change goes through a :class:`~pymotoros.controller.readiness.Readiness`
    method, so the motion-ready flag it shows is never stale.
    """

    _readiness: Readiness
    _inc_move: IncMoveTask
    _trajectory: TrajectoryPoints
    _skills: SkillListeners

    # ---------------------------------------------------------------- readiness
    @property
    def motion_ready(self) -> bool:
        """MotoROS's flag, as its status monitor last saw the signals (§4.1)."""
        return self._readiness.flags.motion_ready

    @property
    def job_ready(self) -> bool:
        return self._readiness.flags.latches.job_ready

    @property
    def inc_move_error(self) -> bool:
        return self._readiness.flags.latches.inc_move_error

    @property
    def pfl_during_move(self) -> bool:
        return self._readiness.flags.latches.pfl_during_move

    @property
    def skill_flags(self) -> tuple[bool, bool]:
        return self._readiness.flags.latches.skill_flags

    @property
    def next_monitor_ms(self) -> int:
        return self._readiness.monitor.next_monitor_ms

    def latch_inc_move_error(self, reason: str) -> None:
        """Set the 5012 latch as the IncMove task does (tests)."""
        self._readiness.flags.latch_inc_move_error(reason)

    def clear_pfl_latch(self) -> None:
        self._readiness.flags.clear_pfl_latch()

    def not_ready_reason(self) -> tuple[int, str, str, str]:
        """(subcode, name, meaning, what clears it) that CHECK_MOTION_READY would give now,
        for the web pendant (subcode 0 UNSPECIFIED when ready)."""
        reasons = self._readiness.reasons
        sub = reasons.subcode()
        return int(sub), sub.name, sub.meaning, reasons.why(sub)

    def clear_inc_move_error(self) -> None:
        self._readiness.flags.clear_inc_move_error()

    def forget_job_ready(self) -> None:
        """Lose job-ready without an OT#889 edge (tests of the 5010 subcode)."""
        self._readiness.flags.forget_job_ready()

    def status_update(self) -> None:
        self._readiness.status_update()

    def on_skill(self, slave: int, text: str) -> None:
        self._skills.on_skill(slave, text)

    # ---------------------------------------------------------------- per group
    @property
    def axes(self) -> tuple[GroupAxes, ...]:
        return self._inc_move.axes

    @property
    def interpolators(self) -> tuple[GroupInterpolator, ...]:
        return self._inc_move.interpolators

    @property
    def jog_tool(self) -> list[int]:
        return self._trajectory.jog_tool

    # ---------------------------------------------------------------- IncMove
    @property
    def waiting(self) -> bool:
        return self._inc_move.waiting

    @property
    def unprocessed_pulses(self) -> tuple[tuple[int, ...], ...]:
        return self._inc_move.unprocessed_pulses
