"""The cell's safety functions: one module each, ticking with the controller.

Like the real safety unit, these act only through the IO image (the PFL signals), the
operator state, and the controller's own execution of increments (the FSU clip, the
PFL retreat). MotoROS never calls into them: it sees them through the signals its
status monitor reads and the results of its incremental-move calls. The unit receives
all of it when it is built (:func:`~pymotoros.controller.assembly.assemble`): the IO
image, the axes and servos, the operator state as an
:class:`~pymotoros.controller.ports.OperatorPort` (read it, raise an alarm, cut servo
power) and the kinematics as the FSU's ``tcp_limiter``; nothing is plugged in later.

Adding a fault is three source files (docs/architecture.md counts them): (1) its
module here, with its test, acting through the ports the unit received (a fault that
raises an alarm or cuts servo power takes ``operator``); (2) this file: built in
:meth:`SafetyUnit.__init__`, ticked in :meth:`SafetyUnit.tick` if it has a time
behaviour, its state filled in :meth:`SafetyUnit.snapshot`, and its action declared in
:data:`SAFETY_ACTIONS` (the unit declares its functions' actions, as it builds them; the
action's call reaches the module through ``target.safety``, so it needs no facade
method); (3) the field it shows, on :class:`SafetySnapshot` in ``controller/values.py``
(the leaf where the controller's values are declared). ``controller/actions.py``
includes :data:`SAFETY_ACTIONS` in the control surface, so the endpoint, its OpenAPI
body, the scenario action and the pendant's list follow, and ``GET /api/state``, its
schema, ``/ws/state`` and ``pymotoros status --api`` show the new field, with no other
edit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final, Protocol

from pymotoros.controller.action_spec import ActionParamError, ActionSpec, Param, Params
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.ports import OperatorPort
from pymotoros.controller.safety.fsu import (
    TCP_NEEDS_KINEMATICS,
    FsuFunction,
    IncrementLimiter,
)
from pymotoros.controller.safety.pfl import (
    DEFAULT_RETREAT_MS,
    MAX_RETREAT_MS,
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
    "SAFETY_ACTIONS",
    "TCP_NEEDS_KINEMATICS",
    "FsuFunction",
    "FsuLimits",
    "IncrementLimiter",
    "PflFunction",
    "PflPhase",
    "PflRefusedError",
    "PflStatus",
    "SafetySnapshot",
    "SafetyTarget",
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


# ------------------------------------------------------------------ the functions' actions


class SafetyTarget(Protocol):
    """What the safety functions' actions act on: the unit itself, so a new function's
    action calls its module (``target.safety.door``) with no facade method, and the PFL
    event, which needs the controller's time and whether the robot moves.
    ``controller/api.py``'s ``SafetyPanel`` extends it; ``VirtualController`` implements
    it."""

    @property
    def safety(self) -> SafetyUnit:
        """The cell's safety unit (its functions: ``pfl``, ``fsu``, ...)."""
        ...

    def pfl_event(self, event: str, *, retreat_ms: int = ..., stop_ms: int = ...) -> None:
        """A PFL "contact" or "clamping" (retreating ``retreat_ms``) now."""
        ...


def _retreat_only_for_clamping(p: Params) -> ActionParamError | None:
    if p.get("retreat_ms") is not None and p.get("event") != "clamping":
        return ActionParamError("retreat_ms", "applies to a clamping only")
    return None


def _fsu_something(p: Params) -> ActionParamError | None:
    limits = p.get("joint_speed_pct") is not None or p.get("tcp_speed_mm_s") is not None
    if p.get("off") and limits:
        return ActionParamError("off", "give either off = true or limits, not both")
    if not limits and not p.get("off"):
        return ActionParamError("", "needs joint_speed_pct, tcp_speed_mm_s or off = true")
    return None


def _pfl(target: SafetyTarget, p: Params) -> None:
    kwargs = {k: p[k] for k in ("retreat_ms", "stop_ms") if p[k] is not None}
    target.pfl_event(p["event"], **kwargs)


SAFETY_ACTIONS: Final[tuple[ActionSpec[SafetyTarget], ...]] = (
    ActionSpec(
        "pfl",
        "/api/pfl",
        "A PFL contact (PFL stop) or clamping (stop, then retreat with PFL escape).",
        _pfl,
        (
            Param(
                "event",
                "str",
                "contact: PFL stop; clamping: PFL stop, then retreat with PFL escape",
                choices=("contact", "clamping"),
            ),
            Param(
                "retreat_ms",
                "int",
                "clamping only: how much of the last motion to retreat",
                unit="ms",
                required=False,
                ge=1,
                le=MAX_RETREAT_MS,
            ),
            Param(
                "stop_ms",
                "int",
                "how long PFL stop stays on (default 500)",
                unit="ms",
                required=False,
                ge=0,
                le=60_000,
            ),
        ),
        rules=(_retreat_only_for_clamping,),
        tag="safety",
    ),
    ActionSpec(
        "fsu",
        "/api/fsu",
        "Switch the FSU speed limits at run time (the cell file's value is the boot value).",
        lambda t, p: t.safety.fsu.set(
            joint_speed_pct=p["joint_speed_pct"],
            tcp_speed_mm_s=None if p["tcp_speed_mm_s"] is None else float(p["tcp_speed_mm_s"]),
            off=bool(p["off"]),
        ),
        (
            Param(
                "joint_speed_pct",
                "int",
                "share of each axis's maximum speed",
                unit="%",
                required=False,
                ge=1,
                le=100,
            ),
            Param(
                "tcp_speed_mm_s",
                "number",
                "TCP speed limit (needs the kinematics model)",
                unit="mm/s",
                required=False,
                gt=0,
            ),
            Param("off", "bool", "switch every FSU speed limit off", required=False, default=False),
        ),
        rules=(_fsu_something,),
        tag="safety",
    ),
)
"""The safety functions' actions, declared with the unit that builds the functions
(``controller/actions.py`` puts them into the control surface, in this order)."""
