"""Whether motion is possible: MotoROS's view of the controller (reference §2.6, §3.6, §4).

:class:`Readiness` composes the three parts of that view, each testable on its own:

- :class:`~pymotoros.controller.ready_flags.ReadyFlags`: the flags of ``Controller.h``
  (motion-ready, job-ready, stop, PFL and inc-move-error latches, the DX100 skill
  flags), the one place motion-ready is computed;
- :class:`~pymotoros.controller.status_monitor.StatusMonitor`: the 10 ms status monitor
  (Ros_Controller_StatusUpdate) and its queue-clearing edges;
- :class:`~pymotoros.controller.not_ready.NotReadyReasons`: the NOT_READY subcode
  order with the specifics behind it.

Everything that needs to know whether motion is possible asks it.
"""

from __future__ import annotations

from typing import Final

from pymotoros.controller.api import Outcome
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.not_ready import NotReadyReasons
from pymotoros.controller.ready_flags import ReadyFlags
from pymotoros.controller.status_monitor import StatusMonitor
from pymotoros.controller.status_reading import (
    BOOT_READING,
    STATUS_PERIOD_MS,
    StatusReading,
    pfl_signals_active,
)
from pymotoros.protocol.constants import ResultCode

__all__ = [
    "BOOT_READING",
    "STATUS_PERIOD_MS",
    "Readiness",
    "StatusReading",
    "pfl_signals_active",
]


class Readiness:
    """The flags, the status monitor that feeds them, and the NOT_READY reasons.

    The flags are read-only from outside: each change goes through a
    :class:`~pymotoros.controller.ready_flags.ReadyFlags` method or the monitor, and
    each of them recomputes the motion-ready flag, so no caller can leave it stale.
    """

    def __init__(self, ctx: MotoRosContext) -> None:
        self.flags: Final = ReadyFlags(
            pfl_option=ctx.cell.pfl,
            dx100=ctx.cell.controller.skillsnd,
            num_groups=ctx.num_groups,
        )
        self.monitor: Final = StatusMonitor(ctx, self.flags)
        self.reasons: Final = NotReadyReasons(ctx, self.flags)
        self.pfl_option: Final = ctx.cell.pfl
        """The PFL option flag read at start-up (GP_isPflEnabled)."""

    @property
    def motion_ready(self) -> bool:
        """§4.1, as of the status monitor's last reading and the current flags."""
        return self.flags.motion_ready

    @property
    def reading(self) -> StatusReading:
        """The status monitor's last reading (§2.6)."""
        return self.flags.reading

    def status_update(self) -> None:
        """Run the status monitor now (Ros_Controller_StatusUpdate)."""
        self.monitor.status_update()

    def not_ready(
        self, result: ResultCode = ResultCode.NOT_READY, group_no: int | None = None
    ) -> Outcome:
        """The NOT_READY refusal for the current state (§4.2)."""
        return self.reasons.outcome(result, group_no)
