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
from typing import Final

from pymotoros.controller.status_reading import BOOT_READING, StatusReading, pfl_signals_active

logger = logging.getLogger(__name__)


class ReadyFlags:
    """The flags of ``Controller.h`` and the status reading they follow."""

    def __init__(self, *, pfl_option: bool, dx100: bool, num_groups: int) -> None:
        self.pfl_option: Final = pfl_option
        """The PFL option flag read at start-up (GP_isPflEnabled)."""
        self._dx100 = dx100
        self._num_groups = num_groups
        self._motion_ready = False
        self._job_ready = False
        self._stop_flag = False
        self._pfl_during_move = False
        self._inc_move_error = False
        self._inc_move_error_reason = ""
        self._skill_flags = (False, False)
        self._r = BOOT_READING

    # ================================================================== read-only

    @property
    def reading(self) -> StatusReading:
        """The status monitor's last reading (§2.6)."""
        return self._r

    @property
    def motion_ready(self) -> bool:
        """§4.1, as of the status monitor's last reading and the current flags."""
        return self._motion_ready

    @property
    def job_ready(self) -> bool:
        """Set on a rising edge of OT#889, cleared on its falling edge."""
        return self._job_ready

    @property
    def stopping(self) -> bool:
        """StopMotion is in progress (§3.6)."""
        return self._stop_flag

    @property
    def pfl_during_move(self) -> bool:
        """The "PFL during ROS move" latch behind 5011 (§4.4)."""
        return self._pfl_during_move

    @property
    def inc_move_error(self) -> bool:
        """The inc-move-error latch behind 5012 (§5.6 step 6)."""
        return self._inc_move_error

    @property
    def inc_move_error_reason(self) -> str:
        """Why the last increment was refused (the NOT_READY detail of 5012)."""
        return self._inc_move_error_reason

    @property
    def skill_flags(self) -> tuple[bool, bool]:
        """DX100 SKILLSND "ROS-START" flags for slave 1 and slave 2 (§4.3)."""
        return self._skill_flags

    @property
    def pfl_active(self) -> bool:
        """§4.1: only with the PFL option on YRC1000 / YRC1000micro builds."""
        return self.pfl_option and (self._pfl_during_move or self._r.pfl_active)

    # ================================================================== changing them

    def observe(self, reading: StatusReading, *, job_ready: bool, pfl_event: bool) -> None:
        """The status monitor's run: its reading, the job-ready edge and a PFL event."""
        self._job_ready = job_ready
        if pfl_event:
            self._pfl_during_move = True
        self._r = reading
        self._refresh()

    def latch_pfl_event(self) -> None:
        """An increment was refused for a PFL reason: 5011 until the next START_TRAJ_MODE."""
        self._pfl_during_move = True
        self._refresh()

    def latch_inc_move_error(self, reason: str) -> None:
        """An increment was refused: 5012 until the next START_TRAJ_MODE (§5.6 step 6)."""
        self._inc_move_error = True
        self._inc_move_error_reason = reason
        self._refresh()

    def clear_latches(self) -> None:
        """START_TRAJ_MODE step 1: clear the PFL and inc-move-error latches (§3.2)."""
        self._pfl_during_move = False
        self._inc_move_error = False
        self._refresh()

    def clear_pfl_latch(self) -> None:
        """Clear only the PFL latch (tests peel the NOT_READY conditions off one by one)."""
        self._pfl_during_move = False
        self._refresh()

    def clear_inc_move_error(self) -> None:
        """Clear only the inc-move-error latch (tests, as :meth:`clear_pfl_latch`)."""
        self._inc_move_error = False
        self._refresh()

    def forget_job_ready(self) -> None:
        """Lose the job-ready flag without an OT#889 edge (tests: the 5010 case of §4.2)."""
        self._job_ready = False
        self._refresh()

    def begin_stop(self) -> None:
        """StopMotion raises the stop flag: motion is not ready while it stops (§3.6)."""
        self._stop_flag = True
        self._refresh()

    def end_stop(self) -> None:
        """StopMotion is done: lower the stop flag."""
        self._stop_flag = False
        self._refresh()

    def set_skill_flag(self, slave: int, on: bool) -> None:
        """A SKILLSND "ROS-START" (on) or "ROS-STOP" (off) reached slave 1 or 2 (§4.3)."""
        flags = list(self._skill_flags)
        flags[slave - 1] = on
        self._skill_flags = (flags[0], flags[1])
        self._refresh()

    def clear_skill_flags(self) -> None:
        """The skill commands ended with the job (§4.3)."""
        self._skill_flags = (False, False)
        self._refresh()

    # ================================================================== the computation

    def _refresh(self) -> None:
        """The one place the motion-ready flag is computed (§4.1)."""
        r = self._r
        ready = self.ready_for(self._job_ready, r.operating, r.remote, self._pfl_during_move, r.pfl)
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
            and not self._inc_move_error
            and not self._stop_flag
        )
        if ready and self._dx100:
            skill = self._skill_flags
            ready = skill[0] and (self._num_groups < 2 or skill[1])
        return ready

    def missing_skills(self) -> tuple[int, ...]:
        """The slaves (1, 2) whose SKILLSND "ROS-START" the DX100 still waits for."""
        if not self._dx100:
            return ()
        return tuple(
            slave
            for slave in range(1, min(self._num_groups, 2) + 1)
            if not self._skill_flags[slave - 1]
        )
