"""The cell's safety functions: one module each, ticking with the controller.

Like the real safety unit, these act only through the IO image (the PFL signals), the
operator state, and the controller's own execution of increments (the FSU clip, the
PFL retreat). MotoROS never calls into them: it sees them through the signals its
status monitor reads and the results of its incremental-move calls.

Adding a fault means one module here (with its test), its declaration in
``controller/actions.py`` (which gives it its control-API endpoint, its scenario action
and its place in the pendant's list) and the state it shows in the controller's
snapshot.
"""

from __future__ import annotations

from collections.abc import Sequence

from pymotoros.controller.io_image import IoImage
from pymotoros.controller.safety.fsu import (
    TCP_NEEDS_KINEMATICS,
    FsuFunction,
    FsuLimits,
    IncrementLimiter,
)
from pymotoros.controller.safety.pfl import (
    DEFAULT_RETREAT_MS,
    PFL_STOP_MS,
    PflFunction,
    PflRefusedError,
    PflStatus,
)
from pymotoros.controller.servo import ServoGroup
from pymotoros.motion import GroupAxes

__all__ = [
    "DEFAULT_RETREAT_MS",
    "PFL_STOP_MS",
    "TCP_NEEDS_KINEMATICS",
    "FsuFunction",
    "FsuLimits",
    "IncrementLimiter",
    "PflFunction",
    "PflRefusedError",
    "PflStatus",
    "SafetyUnit",
]


class SafetyUnit:
    """The PFL and FSU functions of one controller."""

    def __init__(
        self,
        io: IoImage,
        axes: Sequence[GroupAxes],
        servos: Sequence[ServoGroup],
        *,
        period_ms: int,
        pfl_enabled: bool,
        pfl_why_disabled: str,
        fsu_boot_pct: int | None,
    ) -> None:
        self.pfl = PflFunction(
            io, servos, enabled=pfl_enabled, why_disabled=pfl_why_disabled, period_ms=period_ms
        )
        self.fsu = FsuFunction(axes, servos, fsu_boot_pct)

    def tick(self, now_ms: int) -> bool:
        """One interpolation period, before MotoROS's IncMove; True if it moved the servos."""
        pfl = self.pfl
        phase = pfl.phase
        if phase == "idle":  # the common case, and a cell without PFL: nothing to do
            return False
        pfl.tick(now_ms)
        return phase == "escape"
