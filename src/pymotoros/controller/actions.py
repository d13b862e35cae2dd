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
:class:`ActionTarget` here and implemented by the controller. An operator key with
state of its own calls its key directly (``target.keys``, the pendant's keys, which fill
their own part of the snapshot), so it needs no such method; a safety function's action
is declared with the safety unit (``controller/safety/__init__.py``'s
``SAFETY_ACTIONS``, included here) and calls its module through ``target.safety``. The
declaration itself (:class:`ActionSpec`, :class:`Param`, the errors) is the leaf
``controller/action_spec.py``, re-exported here. Nothing else changes: the endpoint,
its schema, the scenario key and the pendant's list follow. A parameter may be an array
of numbers with a length and bounds (a position, a size) or carry its own check (a
shape), and may be given in the path with another method (``DELETE
/api/workspace/{name}``), so issue 21's obstacles are declarations too.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Final, Protocol

from pymotoros.controller.action_spec import (
    ActionParamError,
    ActionRefusedError,
    ActionSpec,
    Param,
    ParamKind,
    Params,
    Rule,
    actions_by_name,
)
from pymotoros.controller.api import FaultInjection, OperatorPanel, SafetyPanel
from pymotoros.controller.safety import SAFETY_ACTIONS
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


Call = Callable[[ActionTarget, Params], None]
"""What an action of the whole surface does: the controller method it calls, with every
declared parameter (optional ones at their default when not given)."""


# --------------------------------------------------------------------------- rules


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

CONTROL_ACTIONS: Final[tuple[ActionSpec[ActionTarget], ...]] = (
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
    *SAFETY_ACTIONS,
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
