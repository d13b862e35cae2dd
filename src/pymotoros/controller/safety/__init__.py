"""The cell's safety functions: one module each, ticking with the controller.

Like the real safety unit, these act only through the IO image (the PFL signals), the
operator state, and the controller's own execution of increments (the FSU clip, the
PFL retreat). MotoROS never calls into them: it sees them through the signals its
status monitor reads and the results of its incremental-move calls.

Adding a fault means one module here (with its test), its declaration in
``controller/actions.py`` (which gives it its control-API endpoint, its scenario action
and its place in the pendant's list; its call reaches the module through
``target.safety``) and the state it shows: a field of :class:`SafetySnapshot`, filled
by :meth:`SafetyUnit.snapshot` (the part is declared with the controller's other values
in ``controller/values.py``, a leaf). The controller's snapshot carries that part, and
``GET /api/state``, its schema, ``/ws/state`` and ``pymotoros status --api`` show each
of its fields with no other edit (docs/architecture.md counts the files).
"""

from __future__ import annotations

from collections.abc import Sequence

from pymotoros.controller.io_image import IoImage
from pymotoros.controller.safety.fsu import (
    TCP_NEEDS_KINEMATICS,
    FsuFunction,
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
from pymotoros.controller.values import FsuLimits, PflPhase, SafetySnapshot
from pymotoros.motion import GroupAxes

__all__ = [
    "DEFAULT_RETREAT_MS",
    "PFL_STOP_MS",
    "TCP_NEEDS_KINEMATICS",
    "FsuFunction",
    "FsuLimits",
    "IncrementLimiter",
    "PflFunction",
    "PflPhase",
    "PflRefusedError",
    "PflStatus",
    "SafetySnapshot",
    "SafetyUnit",
]

_PFL_PHASES: dict[str, PflPhase] = {"idle": "idle", "stop": "stop", "escape": "escape"}


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

    def snapshot(self) -> SafetySnapshot:
        """Each function's state, frozen, for the controller's snapshot."""
        pfl = self.pfl
        phase: PflPhase = "off"
        if pfl.enabled:
            phase = _PFL_PHASES[pfl.phase]
        return SafetySnapshot(fsu=self.fsu.active, pfl=phase)

    def tick(self, now_ms: int) -> bool:
        """One interpolation period, before MotoROS's IncMove; True if it moved the servos."""
        pfl = self.pfl
        phase = pfl.phase
        if phase == "idle":  # the common case, and a cell without PFL: nothing to do
            return False
        pfl.tick(now_ms)
        return phase == "escape"
