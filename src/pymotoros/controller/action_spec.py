"""How an action of the control surface is declared: :class:`ActionSpec` and its :class:`Param`.

A leaf: it imports nothing from the rest of :mod:`pymotoros.controller`, so a part of
the controller can declare its own actions next to the code they drive (the safety unit
declares its functions' actions in ``controller/safety/__init__.py``, which
``controller/actions.py`` imports) without an import cycle. ``controller/actions.py``
gathers every declaration into :data:`~pymotoros.controller.actions.CONTROL_ACTIONS`
and re-exports these names, the place users import them from.

An :class:`ActionSpec` is generic in what its call acts on (``TargetT``, contravariant):
an action that needs only the safety unit is an ``ActionSpec[SafetyTarget]``, and so also
an action of the whole surface (``ActionSpec[ActionTarget]``, whose target has the safety
unit among everything else), while mypy still checks its call against the methods it
uses.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final, Generic, Literal, TypeVar

from pymotoros.errors import PymotorosError

__all__ = [
    "ActionParamError",
    "ActionRefusedError",
    "ActionSpec",
    "Param",
    "ParamKind",
    "Params",
    "Rule",
    "TargetT",
    "actions_by_name",
]

TargetT = TypeVar("TargetT", contravariant=True)
"""What an action's call acts on: an action that needs less than the whole control
surface is an action of the whole surface too."""
T = TypeVar("T")

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


@dataclass(frozen=True, slots=True)
class ActionSpec(Generic[TargetT]):
    """One action of the control surface, declared once for every surface; ``TargetT``
    is what its call needs of the controller (``ActionTarget`` for the whole surface)."""

    name: str
    """The scenario file's ``action`` and the pendant's name for it."""
    path: str
    """The control API's path; a parameter named in braces (``/api/workspace/{name}``)
    is given in the path, the others in the JSON body."""
    doc: str
    """What the action does (the endpoint's description, the pendant's tooltip)."""
    call: Callable[[TargetT, Params], None]
    """What the action does: the method it calls on its target, with every declared
    parameter (optional ones at their default when not given)."""
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

    def perform(self, target: TargetT, params: Params) -> None:
        """Run the action with checked parameters; what the controller refuses raises
        :class:`ActionRefusedError` (our error, with the controller's words)."""
        self.check_rules(params)
        try:
            self.call(target, self.complete(params))
        except PymotorosError:
            raise
        except ValueError as exc:  # the controller's documented refusal (OperatorPanel)
            raise ActionRefusedError(str(exc)) from exc


def actions_by_name(actions: Sequence[ActionSpec[T]]) -> dict[str, ActionSpec[T]]:
    """The actions keyed by name; a name or path declared twice is a bug."""
    out: dict[str, ActionSpec[T]] = {}
    paths: set[str] = set()
    for spec in actions:
        if spec.name in out or spec.path in paths:
            raise ValueError(f"action {spec.name!r} ({spec.path}) is declared twice")
        out[spec.name] = spec
        paths.add(spec.path)
    return out
