"""The cell's safety functions: one module each, ticking with the controller.

Like the real safety unit, these act only through the IO image (the PFL signals), the
operator state, and the controller's own execution of increments (the FSU clip, the
PFL retreat). MotoROS never calls into them: it sees them through the signals its
status monitor reads and the results of its incremental-move calls. The unit receives
all of it when it is built (:func:`~pymotoros.controller.assembly.assemble`): the IO
image, the axes and servos, the operator state as an
:class:`~pymotoros.controller.ports.OperatorPort` (read it, raise an alarm, cut servo
power) and the kinematics as the FSU's ``tcp_limiter``; nothing is plugged in later.

Adding a fault means one module here (with its test), built in
:meth:`SafetyUnit.__init__` from those ports (a fault that raises an alarm takes
``operator``), its declaration in ``controller/actions.py`` (which gives it its
control-API endpoint, its scenario action and its place in the pendant's list; its call
reaches the module through ``target.safety``) and the state it shows: a field of
:class:`SafetySnapshot`, filled by :meth:`SafetyUnit.snapshot` (the part is declared
with the controller's other values in ``controller/values.py``, a leaf). The
controller's snapshot carries that part, and ``GET /api/state``, its schema,
``/ws/state`` and ``pymotoros status --api`` show each of its fields with no other edit
(docs/architecture.md counts the files).
"""

from __future__ import annotations

from collections.abc import Sequence

from pymotoros.controller.io_image import IoImage
from pymotoros.controller.ports import OperatorPort
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
        operator: OperatorPort,
        tcp_limiter: IncrementLimiter | None,
        period_ms: int,
        pfl_enabled: bool,
        pfl_why_disabled: str,
        fsu_boot_pct: int | None,
    ) -> None:
        """``operator``: the operator state the functions read and act on (alarms, servo
        power); ``tcp_limiter``: the kinematics the FSU's TCP-speed limit needs (None:
        that limit is refused)."""
        self.operator = operator
        """The operator state as the safety functions reach it (a fault that raises an
        alarm or cuts servo power acts through it; so does the workspace contact)."""
        self.pfl = PflFunction(
            io, servos, enabled=pfl_enabled, why_disabled=pfl_why_disabled, period_ms=period_ms
        )
        self.fsu = FsuFunction(axes, servos, fsu_boot_pct, tcp_limiter=tcp_limiter)

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
