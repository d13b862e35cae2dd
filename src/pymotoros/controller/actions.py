"""The control surface, declared once: every operator, safety and fault action.

Each :class:`ActionSpec` says, in one place, an action's name, its typed and
range-checked parameters (:class:`Param`: kind, unit, documentation, bounds), the rules
between its parameters, and the controller method it calls. Every surface is derived
from these declarations, so a value one surface refuses is refused by every surface
with the same message:

* the control API (``runtime/http_api.py``): one ``POST`` endpoint per action, its
  pydantic body and OpenAPI schema built from the parameters;
* scenario files (``controller/scenario.py``, which takes these declarations as its
  argument and declares the one action that loads a scenario over them): the ``action``
  of an ``[[events]]`` table and its keys, validated by :meth:`ActionSpec.check_value`
  and the rules;
* the web pendant (``runtime/pendant``): ``GET /api/pendant/actions`` lists the actions
  its buttons call, with their paths and parameters.

A parameter's value is checked by :meth:`ActionSpec.check_value` (a malformed request:
HTTP 422, a scenario file's ConfigError); the rules between parameters by
:meth:`ActionSpec.check_rules` (a refused request: HTTP 400, the same ConfigError at
load time). Either raises :class:`ActionParamError`, whose text is the same on every
surface; the surfaces only add where the value came from. What the controller refuses
when the action runs (a PFL contact while standing still) becomes an
:class:`ActionRefusedError`.

Adding an action is one more :class:`ActionSpec` in :data:`CONTROL_ACTIONS`; when it
calls a controller method that no action called before, that method is declared on
:class:`ActionTarget` here and implemented by the controller. Nothing else changes: the
endpoint, its schema, the scenario key and the pendant's list follow. A parameter may
be an array of numbers with a length and bounds (a position, a size) or carry its own
check (a shape), and may be given in the path with another method
(``DELETE /api/workspace/{name}``), so issue 21's obstacles are declarations too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final, Literal, Protocol

from pymotoros.controller.api import FaultInjection, OperatorPanel, SafetyPanel
from pymotoros.controller.safety.pfl import MAX_RETREAT_MS
from pymotoros.errors import PymotorosError
from pymotoros.models.workspace import MAX_SIZE_M, SHAPE_KEYS, Obstacle, UnknownObstacleError
from pymotoros.protocol.constants import PendantMode

__all__ = [
    "CONTROL_ACTIONS",
    "ActionParamError",
    "ActionRefusedError",
    "ActionSpec",
    "ActionTarget",
    "ActionTargetMissingError",
    "Call",
    "Param",
    "ParamKind",
    "Params",
    "Rule",
    "actions_by_name",
]

ParamKind = Literal["bool", "int", "number", "str", "numbers", "tables"]
"""``number`` takes integers too; ``numbers`` is an array of numbers (a position, a
size: ``length`` of them, each within the bounds); ``tables`` an array of tables (JSON
objects)."""

_KIND_TEXT: Final[Mapping[str, str]] = {
    "bool": "true or false",
    "int": "an integer",
    "number": "a number",
    "str": "a string",
    "numbers": "an array of numbers",
    "tables": "an array of tables",
}


class ActionParamError(PymotorosError, ValueError):
    """A parameter of an action is wrong; ``key`` is the parameter ("" for the action).

    ``str()`` is ``"key: text"``: every surface shows that, after where it came from.
    """

    def __init__(self, key: str, text: str) -> None:
        super().__init__(f"{key}: {text}" if key else text)
        self.key = key
        self.text = text


class ActionRefusedError(PymotorosError, ValueError):
    """The controller refused an action when it ran (the message says why)."""


class ActionTargetMissingError(ActionRefusedError, LookupError):
    """The action names something that is not there (an obstacle to remove that the
    cell does not hold): the control API answers 404, the message names what is there."""


class ActionTarget(OperatorPanel, FaultInjection, SafetyPanel, Protocol):
    """What the actions act on: the operator's panel, fault injection, the safety
    functions. ``VirtualController`` implements it; the runtime's
    ``SimulatedController`` includes it, so a method a new action needs is declared here,
    once."""

    def put_obstacle(self, entry: Mapping[str, object]) -> Obstacle:
        """Add an obstacle or move the one of that name (the cell file's keys; a bad one
        is a ConfigError naming its key)."""
        ...

    def remove_obstacle(self, name: str) -> None:
        """Remove the obstacle ``name`` (ConfigError naming the known ones if none)."""
        ...


Params = Mapping[str, Any]
"""An action's parameters, already checked (each key declared, each value valid)."""


@dataclass(frozen=True, slots=True)
class Param:
    """One parameter of an action: its kind, bounds, unit and meaning."""

    name: str
    kind: ParamKind
    doc: str
    unit: str = ""
    required: bool = True
    default: Any = None
    """The value when an optional parameter is not given (None: the controller's own)."""
    choices: tuple[str, ...] = ()
    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    max_length: int | None = None
    """A string's longest length."""
    length: int | None = None
    """How many numbers a ``numbers`` parameter holds (None: any)."""
    check: Callable[[Any], str | None] | None = None
    """A check beyond kind and bounds (e.g. an obstacle's shape): why the value is wrong,
    or None. Runs on every surface like the others."""

    @property
    def description(self) -> str:
        """The documentation with the unit, as the OpenAPI schema shows it."""
        return f"{self.doc} ({self.unit})" if self.unit else self.doc

    def bounds_text(self) -> str:
        """The range in words: "1..100 %", ">= 0", "> 0 mm/s" ("" when unbounded)."""
        unit = f" {self.unit}" if self.unit else ""
        lo = self.ge if self.ge is not None else self.gt
        if lo is not None and self.le is not None and self.gt is None:
            return f"{_num(lo)}..{_num(self.le)}{unit}"
        parts = []
        if self.ge is not None:
            parts.append(f">= {_num(self.ge)}")
        if self.gt is not None:
            parts.append(f"> {_num(self.gt)}")
        if self.le is not None:
            parts.append(f"<= {_num(self.le)}")
        return " and ".join(parts) + unit if parts else ""

    def problem(self, value: object) -> str | None:
        """Why ``value`` is not valid for this parameter (None: it is)."""
        kind = self.kind
        if kind == "bool":
            ok = isinstance(value, bool)
        elif kind == "int":
            ok = isinstance(value, int) and not isinstance(value, bool)
        elif kind == "number":
            ok = _is_number(value)
        elif kind == "str":
            ok = isinstance(value, str)
        elif kind == "numbers":
            ok = isinstance(value, list) and all(_is_number(v) for v in value)
        else:
            ok = isinstance(value, list) and all(isinstance(v, Mapping) for v in value)
        if not ok:
            return f"must be {_KIND_TEXT[kind]}, not {value!r}"
        problem = self._value_problem(value)
        if problem is None and self.check is not None:
            problem = self.check(value)
        return problem

    def _value_problem(self, value: Any) -> str | None:
        """Choices, bounds and lengths of a value of the right kind."""
        if self.choices and value not in self.choices:
            return f"must be one of {', '.join(self.choices)}, not {value!r}"
        if self.kind in ("int", "number"):
            return self._range_problem(value)
        if self.kind == "numbers":
            if self.length is not None and len(value) != self.length:
                return f"must hold {self.length} numbers, not {len(value)}"
            for i, v in enumerate(value):
                problem = self._range_problem(v)
                if problem is not None:
                    return f"[{i}] {problem}"
        if self.max_length is not None and isinstance(value, str) and len(value) > self.max_length:
            return f"must be at most {self.max_length} characters, not {len(value)}"
        return None

    def _range_problem(self, number: int | float) -> str | None:
        # compared as given: an integer of any size never goes through float()
        if isinstance(number, float) and not math.isfinite(number):
            return f"must be a finite number, not {number!r}"
        if (
            (self.ge is not None and number < self.ge)
            or (self.gt is not None and number <= self.gt)
            or (self.le is not None and number > self.le)
        ):
            verb = "must lie in" if ".." in self.bounds_text() else "must be"
            return f"{verb} {self.bounds_text()}, not {number!r}"
        return None


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _num(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else repr(value)


Rule = Callable[[Params], ActionParamError | None]
"""A rule between an action's parameters: the error when the parameters break it."""

Call = Callable[[ActionTarget, Params], None]
"""What the action does: the controller method it calls, with every declared parameter
(optional ones at their default when not given)."""


@dataclass(frozen=True, slots=True)
class ActionSpec:
    """One action of the control surface, declared once for every surface."""

    name: str
    """The scenario file's ``action`` and the pendant's name for it."""
    path: str
    """The control API's path; a parameter named in braces (``/api/workspace/{name}``)
    is given in the path, the others in the JSON body."""
    doc: str
    """What the action does (the endpoint's description, the pendant's tooltip)."""
    call: Call
    params: tuple[Param, ...] = ()
    rules: tuple[Rule, ...] = ()
    tag: str = "operator"
    """The OpenAPI tag: operator, io, safety."""
    in_scenarios: bool = True
    """Whether a scenario event may carry it (loading a scenario may not)."""
    method: Literal["POST", "PUT", "DELETE"] = "POST"
    """The control API's method (DELETE for removing something by name)."""

    @property
    def path_keys(self) -> tuple[str, ...]:
        """The parameters given in the path."""
        return tuple(p.name for p in self.params if "{" + p.name + "}" in self.path)

    def param(self, key: str) -> Param | None:
        for p in self.params:
            if p.name == key:
                return p
        return None

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    def check_value(self, key: str, value: object) -> None:
        """Refuse a declared parameter's bad value (ActionParamError)."""
        p = self.param(key)
        if p is None:  # the surfaces refuse unknown keys in their own words first
            raise ActionParamError(key, f"unknown key for action {self.name!r}")
        problem = p.problem(value)
        if problem is not None:
            raise ActionParamError(key, problem)

    def check_values(self, params: Mapping[str, object]) -> None:
        """Check every declared parameter that ``params`` gives, in declaration order."""
        for p in self.params:
            if p.name in params:
                self.check_value(p.name, params[p.name])

    def check_rules(self, params: Params) -> None:
        """Refuse parameters that break a rule between them (ActionParamError)."""
        for rule in self.rules:
            error = rule(params)
            if error is not None:
                raise error

    def complete(self, params: Params) -> dict[str, Any]:
        """``params`` with every optional parameter not given at its default."""
        return {p.name: params.get(p.name, p.default) for p in self.params}

    def perform(self, target: ActionTarget, params: Params) -> None:
        """Run the action with checked parameters; what the controller refuses raises
        :class:`ActionRefusedError` (our error, with the controller's words)."""
        self.check_rules(params)
        try:
            self.call(target, self.complete(params))
        except PymotorosError:
            raise
        except ValueError as exc:  # the controller's documented refusal (OperatorPanel)
            raise ActionRefusedError(str(exc)) from exc


def actions_by_name(actions: Sequence[ActionSpec]) -> dict[str, ActionSpec]:
    """The actions keyed by name; a name or path declared twice is a bug."""
    out: dict[str, ActionSpec] = {}
    paths: set[str] = set()
    for spec in actions:
        if spec.name in out or spec.path in paths:
            raise ValueError(f"action {spec.name!r} ({spec.path}) is declared twice")
        out[spec.name] = spec
        paths.add(spec.path)
    return out


# --------------------------------------------------------------------------- rules


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


def _one_shape(p: Params) -> ActionParamError | None:
    given = [k for k in SHAPE_KEYS if p.get(k) is not None]
    if len(given) != 1:
        problem = "gives none" if not given else f"gives {' and '.join(given)}"
        return ActionParamError(
            "", f"an obstacle has exactly one of box, cylinder, sphere; it {problem}"
        )
    return None


# --------------------------------------------------------------------------- calls


def _put_obstacle(target: ActionTarget, p: Params) -> None:
    target.put_obstacle({k: v for k, v in p.items() if v is not None})


def _remove_obstacle(target: ActionTarget, p: Params) -> None:
    try:
        target.remove_obstacle(p["name"])
    except UnknownObstacleError as exc:
        raise ActionTargetMissingError(str(exc)) from exc


def _obstacle_name(value: object) -> str | None:
    if not isinstance(value, str) or not value.strip() or "/" in value:
        return "must be a non-empty name without '/'"
    return None


def _pfl(target: ActionTarget, p: Params) -> None:
    kwargs = {k: p[k] for k in ("retreat_ms", "stop_ms") if p[k] is not None}
    target.pfl_event(p["event"], **kwargs)


def _fsu(target: ActionTarget, p: Params) -> None:
    tcp = p["tcp_speed_mm_s"]
    target.set_fsu(
        joint_speed_pct=p["joint_speed_pct"],
        tcp_speed_mm_s=None if tcp is None else float(tcp),
        off=bool(p["off"]),
    )


def _on(doc: str) -> tuple[Param, ...]:
    return (Param("on", "bool", doc),)


_OBSTACLE_NAME = Param("name", "str", "the obstacle's name", max_length=64, check=_obstacle_name)
_SIZE: Final[dict[str, Any]] = {"unit": "m", "required": False, "gt": 0, "le": MAX_SIZE_M}
_OBSTACLE_PARAMS: Final = (
    _OBSTACLE_NAME,
    Param("box", "numbers", "a box: full sizes [x, y, z]", length=3, **_SIZE),
    Param("cylinder", "numbers", "a cylinder: [radius, length], axis along z", length=2, **_SIZE),
    Param("sphere", "number", "a sphere: its radius", **_SIZE),
    Param(
        "xyz", "numbers", "the centre [x, y, z]", unit="m", length=3, ge=-MAX_SIZE_M, le=MAX_SIZE_M
    ),
    Param(
        "rpy_deg",
        "numbers",
        "orientation [roll, pitch, yaw] (fixed axes X, Y, Z)",
        unit="deg",
        length=3,
        required=False,
    ),
    Param(
        "frame",
        "str",
        "the group whose base_link the pose is given in (default: the workspace frame)",
        required=False,
        max_length=16,
    ),
)

_CODE = Param("code", "int", "alarm number, e.g. 4107", ge=0, le=9999)
_SUBCODE = Param("subcode", "int", "alarm subcode", required=False, default=0, ge=0)
_TEXT = Param(
    "text", "str", "text shown on the pendant", required=False, default="", max_length=128
)

CONTROL_ACTIONS: Final[tuple[ActionSpec, ...]] = (
    ActionSpec(
        "estop",
        "/api/estop",
        "Press or release the pendant E-stop: cuts servo power, stops the job, no alarm.",
        lambda t, p: t.press_estop(p["pressed"]),
        (Param("pressed", "bool", "true presses the pendant E-stop, false releases it"),),
    ),
    ActionSpec(
        "hold",
        "/api/hold",
        "Switch HOLD on or off.",
        lambda t, p: t.set_hold(p["on"]),
        _on("true switches HOLD on"),
    ),
    ActionSpec(
        "mode",
        "/api/mode",
        "Turn the pendant's mode key to TEACH or PLAY.",
        lambda t, p: t.set_mode(PendantMode(p["mode"])),
        (Param("mode", "str", "the mode key's position", choices=("teach", "play")),),
    ),
    ActionSpec(
        "remote",
        "/api/remote",
        "Switch REMOTE on or off.",
        lambda t, p: t.set_remote(p["on"]),
        _on("true switches REMOTE on"),
    ),
    ActionSpec(
        "servo",
        "/api/servo",
        "Request servo power on or off (refused silently while E-stopped).",
        lambda t, p: t.set_servo(p["on"]),
        _on("true requests servo power"),
    ),
    ActionSpec(
        "eco",
        "/api/eco",
        "Enter eco mode (servo power saved; needs servo on) or leave it.",
        lambda t, p: t.set_eco(p["on"]),
        _on("true enters eco mode"),
    ),
    ActionSpec(
        "alarm",
        "/api/alarm",
        "Raise an alarm.",
        lambda t, p: t.raise_alarm(p["code"], p["subcode"], p["text"]),
        (_CODE, _SUBCODE, _TEXT),
    ),
    ActionSpec(
        "error",
        "/api/error",
        "Raise an operator error (not an alarm): motion is refused with 5002 until reset.",
        lambda t, p: t.raise_error(p["code"], p["subcode"], p["text"]),
        (_CODE, _SUBCODE, _TEXT),
    ),
    ActionSpec(
        "reset",
        "/api/reset",
        "The pendant's RESET key: clears alarms and errors whose cause is gone.",
        lambda t, p: t.reset(),
    ),
    ActionSpec(
        "io",
        "/api/io",
        "Force any bit (0/1) or M-register (address 1000000 + n, 0..65535).",
        lambda t, p: t.force_io(p["address"], p["value"]),
        (
            Param(
                "address", "int", "bit address (e.g. 20010), or 1000000 + n for M-register n", ge=0
            ),
            Param("value", "int", "0/1 for a bit, 0..65535 for an M-register", ge=0, le=0xFFFF),
        ),
        tag="io",
    ),
    ActionSpec(
        "io_failure",
        "/api/io/failure",
        "Fault injection: make client IO reads (1004) and/or writes (1005) fail.",
        lambda t, p: t.set_io_api_failure(reads=p["reads"], writes=p["writes"]),
        (
            Param("reads", "bool", "client IO reads fail with 1004", required=False, default=False),
            Param(
                "writes", "bool", "client IO writes fail with 1005", required=False, default=False
            ),
        ),
        tag="io",
    ),
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
        _fsu,
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
    ActionSpec(
        "obstacle",
        "/api/workspace",
        "Put an obstacle into the cell, or move/reshape the one of that name (the cell "
        "file's [[workspace.obstacles]] keys): the twin stops a robot that touches it.",
        _put_obstacle,
        _OBSTACLE_PARAMS,
        rules=(_one_shape,),
        tag="safety",
    ),
    ActionSpec(
        "remove_obstacle",
        "/api/workspace/{name}",
        "Remove the obstacle of that name from the cell (404 when there is none).",
        _remove_obstacle,
        (_OBSTACLE_NAME,),
        tag="safety",
        method="DELETE",
    ),
    ActionSpec(
        "drop_motion",
        "/api/drop_motion",
        "Close the motion connection as a pulled cable would.",
        lambda t, p: t.drop_motion(),
        tag="safety",
    ),
)
"""Every operator, IO, safety and fault action (the order of the OpenAPI document).
The action that loads a scenario, whose events carry these, is declared over them in
``controller/scenario.py`` (:func:`~pymotoros.controller.scenario.with_scenario_of`)."""
