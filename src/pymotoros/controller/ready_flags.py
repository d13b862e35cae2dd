"""MotoROS's flags (``Controller.h``) and the one place the motion-ready flag is computed.

:class:`ReadyFlags` holds the motion-ready, job-ready, stop, PFL and inc-move-error
latches and the DX100 skill flags, together with the status reading they were last
computed from. The flags are read-only from outside: each change goes through an
intention-revealing method (or :meth:`ReadyFlags.observe`, the status monitor's
hand-over), and every one of them ends in :meth:`ReadyFlags._refresh`, so the flag
always agrees with its inputs (§4.1).
"""

from __future__ import annotations

import logging
from typing import Any, Final, NamedTuple

from pymotoros.controller.status_reading import BOOT_READING, StatusReading, pfl_signals_active

logger = logging.getLogger(__name__)


class Latches(NamedTuple):
    """MotoROS's flags besides motion-ready, as one immutable value."""

    job_ready: bool = False
    """Set on a rising edge of OT#889, cleared on its falling edge."""
    stopping: bool = False
    """StopMotion is in progress (§3.6)."""
    pfl_during_move: bool = False
    """The "PFL during ROS move" latch behind 5011 (§4.4)."""
    inc_move_error: bool = False
    """The inc-move-error latch behind 5012 (§5.6 step 6)."""
    inc_move_error_reason: str = ""
    """Why the last increment was refused (the NOT_READY detail of 5012)."""
    skill_flags: tuple[bool, bool] = (False, False)
    """DX100 SKILLSND "ROS-START" flags for slave 1 and slave 2 (§4.3)."""


class ReadyFlags:
    """The flags of ``Controller.h`` and the status reading they follow."""

    def __init__(self, *, pfl_option: bool, dx100: bool, num_groups: int) -> None:
        self.pfl_option: Final = pfl_option
        """The PFL option flag read at start-up (GP_isPflEnabled)."""
        self._dx100 = dx100
        self._num_groups = num_groups
        self._motion_ready = False
        self._latches = Latches()
        self._r = BOOT_READING

    @property
    def reading(self) -> StatusReading:
        """The status monitor's last reading (§2.6)."""
        return self._r

    @property
    def motion_ready(self) -> bool:
        """§4.1, as of the status monitor's last reading and the current flags."""
        return self._motion_ready

    @property
    def latches(self) -> Latches:
        """Job-ready, stop, PFL and inc-move-error latches, skill flags (read-only)."""
        return self._latches

    @property
    def pfl_active(self) -> bool:
        """§4.1: only with the PFL option on YRC1000 / YRC1000micro builds."""
        return self.pfl_option and (self._latches.pfl_during_move or self._r.pfl_active)

    # ================================================================== changing them

    def observe(self, reading: StatusReading, *, job_ready: bool, pfl_event: bool) -> None:
        """The status monitor's run: its reading, the job-ready edge and a PFL event."""
        self._r = reading
        if pfl_event:
            self._change(job_ready=job_ready, pfl_during_move=True)
        else:
            self._change(job_ready=job_ready)

    def latch_pfl_event(self) -> None:
        """An increment was refused for a PFL reason: 5011 until the next START_TRAJ_MODE."""
        self._change(pfl_during_move=True)

    def latch_inc_move_error(self, reason: str) -> None:
        """An increment was refused: 5012 until the next START_TRAJ_MODE (§5.6 step 6)."""
        self._change(inc_move_error=True, inc_move_error_reason=reason)

    def clear_latches(self) -> None:
        """START_TRAJ_MODE step 1: clear the PFL and inc-move-error latches (§3.2)."""
        self._change(pfl_during_move=False, inc_move_error=False)

    def clear_pfl_latch(self) -> None:
        """Clear only the PFL latch (tests peel the NOT_READY conditions off one by one)."""
        self._change(pfl_during_move=False)

    def clear_inc_move_error(self) -> None:
        """Clear only the inc-move-error latch (tests, as :meth:`clear_pfl_latch`)."""
        self._change(inc_move_error=False)

    def forget_job_ready(self) -> None:
        """Lose the job-ready flag without an OT#889 edge (tests: the 5010 case of §4.2)."""
        self._change(job_ready=False)

    def begin_stop(self) -> None:
        """StopMotion raises the stop flag: motion is not ready while it stops (§3.6)."""
        self._change(stopping=True)

    def end_stop(self) -> None:
        """StopMotion is done: lower the stop flag."""
        self._change(stopping=False)

    def set_skill_flag(self, slave: int, on: bool) -> None:
        """A SKILLSND "ROS-START" (on) or "ROS-STOP" (off) reached slave 1 or 2 (§4.3)."""
        flags = list(self._latches.skill_flags)
        flags[slave - 1] = on
        self._change(skill_flags=(flags[0], flags[1]))

    def clear_skill_flags(self) -> None:
        """The skill commands ended with the job (§4.3)."""
        self._change(skill_flags=(False, False))

    def _change(self, **changes: Any) -> None:
        """Every change of a latch ends here, so motion-ready is never stale."""
        self._latches = self._latches._replace(**changes)
        self._refresh()

    # ================================================================== the computation

    def _refresh(self) -> None:
        """The one place the motion-ready flag is computed (§4.1)."""
        r, latches = self._r, self._latches
        ready = self.ready_for(
            latches.job_ready, r.operating, r.remote, latches.pfl_during_move, r.pfl
        )
        if ready != self._motion_ready:
            logger.debug("motion ready: %s", ready)
        self._motion_ready = ready

    def ready_for(
        self,
        job_ready: bool,
        operating: int,
        remote: int,
        pfl_latched: bool,
        pfl: tuple[int, ...],
    ) -> bool:
        """§4.1 for the given reading and latches, with the current stop and skill flags."""
        ready = (
            job_ready
            and operating == 1
            and remote == 1
            and not (self.pfl_option and (pfl_latched or pfl_signals_active(pfl)))
            and not self._latches.inc_move_error
            and not self._latches.stopping
        )
        if ready and self._dx100:
            skill = self._latches.skill_flags
            ready = skill[0] and (self._num_groups < 2 or skill[1])
        return ready

    def missing_skills(self) -> tuple[int, ...]:
        """The slaves (1, 2) whose SKILLSND "ROS-START" the DX100 still waits for."""
        if not self._dx100:
            return ()
        return tuple(
            slave
            for slave in range(1, min(self._num_groups, 2) + 1)
            if not self._latches.skill_flags[slave - 1]
        )
