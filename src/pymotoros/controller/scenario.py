"""Fault scenarios: timed operator and safety events, replayed exactly (virtual or real time).

A scenario is a list of events (TOML ``[[events]]`` tables, or the JSON body of
``POST /api/scenario``). Each event has exactly one trigger and one action:

* triggers: ``at`` (seconds after boot), ``after_motion`` (seconds after the first
  executed increment of the next trajectory: the first to start after the scenario is
  loaded; every ``after_motion`` event counts from that instant), ``when_io``
  (``{address, value}``: as soon as the bit or M-register reads that value);
* actions: every action of :data:`pymotoros.controller.actions.CONTROL_ACTIONS` that a
  scenario may carry (``estop``, ``hold``, ``mode``, ``remote``, ``servo``, ``eco``,
  ``alarm``, ``error``, ``reset``, ``io``, ``io_failure``, ``pfl``, ``fsu``,
  ``obstacle``, ``remove_obstacle``, ``drop_motion``), whose parameters are the keys
  of the matching control-API body, checked by the same declaration, so a value the
  control API refuses is refused here with the same words.

:func:`parse_scenario` is pure and refuses a bad scenario naming the event and the key
(a misspelt key is named with the nearest valid one). :class:`ScenarioDriver` fires the
events from the controller's tick, so a run in virtual time is deterministic.
"""

from __future__ import annotations

import difflib
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Final, TypeGuard

from pymotoros.controller.actions import (
    CONTROL_ACTIONS,
    ActionParamError,
    ActionSpec,
    ActionTarget,
    Call,
    Param,
    Params,
    actions_by_name,
)
from pymotoros.controller.values import Scenario, ScenarioEvent
from pymotoros.errors import ConfigError
from pymotoros.models.toml_file import read_toml

__all__ = [
    "ACTIONS",
    "TRIGGERS",
    "FiredEvent",
    "Scenario",
    "ScenarioDriver",
    "ScenarioEvent",
    "load_scenario",
    "parse_scenario",
    "perform",
    "scenario_action",
    "scenario_loader",
    "with_scenario_of",
]

logger = logging.getLogger(__name__)

TRIGGERS: Final = ("at", "after_motion", "when_io")

ACTIONS: Final[Mapping[str, ActionSpec[ActionTarget]]] = {
    name: spec for name, spec in actions_by_name(CONTROL_ACTIONS).items() if spec.in_scenarios
}
"""Every action a scenario may carry, by name (the declarations of ``actions.py``)."""


def load_scenario(path: str | Path) -> Scenario:
    """Read a scenario TOML file; a mistake raises ConfigError naming the event and key."""
    return parse_scenario(read_toml(path, "scenario file"), source=str(path))


def _seconds(value: object) -> TypeGuard[float]:
    """A finite number >= 0 (TOML's integer or float, not a boolean)."""
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and value >= 0
    )


def parse_scenario(
    data: Mapping[str, object],
    *,
    source: str = "<scenario>",
    actions: Sequence[ActionSpec[ActionTarget]] = CONTROL_ACTIONS,
) -> Scenario:
    """Validate a parsed scenario ({"events": [...]}); refuse anything unknown or wrong.

    ``actions``: the declared actions its events may carry (those with ``in_scenarios``
    false are left out); a surface serving more actions passes its own."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source}: a scenario must be a table with an 'events' array")
    unknown = sorted(set(data) - {"events"})
    if unknown:
        raise ConfigError(f"{source}: {unknown[0]}: unknown key (a scenario has only [[events]])")
    raw = data.get("events")
    if not isinstance(raw, list) or not raw:
        raise ConfigError(f"{source}: events: needs at least one [[events]] table")
    known = (
        ACTIONS
        if actions is CONTROL_ACTIONS
        else {n: a for n, a in actions_by_name(actions).items() if a.in_scenarios}
    )
    return Scenario(tuple(_event(i, e, source, known) for i, e in enumerate(raw)), source)


def _nearest(key: str, valid: Sequence[str]) -> str:
    """The hint " (did you mean 'x'?)" for a misspelt key; "" when nothing is close."""
    close = difflib.get_close_matches(key, valid, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _event(
    i: int, raw: object, source: str, actions: Mapping[str, ActionSpec[ActionTarget]]
) -> ScenarioEvent:
    where = f"{source}: events[{i}]"
    if not isinstance(raw, Mapping):
        raise ConfigError(f"{where}: must be a table")
    spec = actions.get(raw["action"]) if isinstance(raw.get("action"), str) else None
    trigger = _trigger(raw, where, spec)
    action = raw.get("action")
    if spec is None:
        choices = ", ".join(actions)
        hint = _nearest(action, list(actions)) if isinstance(action, str) else ""
        raise ConfigError(f"{where}.action: must be one of {choices}, not {action!r}{hint}")
    where = f"{where} ({spec.name})"
    seconds, io = _trigger_value(raw[trigger], trigger, where)
    params = _params(raw, trigger, spec, where)
    return ScenarioEvent(i, trigger, seconds, io, spec.name, params, spec)


def _trigger(raw: Mapping[str, object], where: str, spec: ActionSpec[ActionTarget] | None) -> str:
    """The event's one trigger; a misspelt one is named with the nearest trigger."""
    triggers = [t for t in TRIGGERS if t in raw]
    if len(triggers) == 1:
        return triggers[0]
    needs = f"needs exactly one trigger of {', '.join(TRIGGERS)}"
    if triggers:
        raise ConfigError(f"{where}: {needs} (found: {', '.join(triggers)})")
    declared = spec.keys if spec is not None else ()
    for key in raw:
        if key != "action" and key not in declared:
            hint = _nearest(str(key), [*TRIGGERS, *declared])
            raise ConfigError(f"{where}.{key}: unknown key{hint}; the event {needs}")
    raise ConfigError(f"{where}: {needs} (found: none)")


def _trigger_value(value: object, trigger: str, where: str) -> tuple[float, tuple[int, int]]:
    """(seconds, (address, value)) of the trigger's value."""
    if trigger in ("at", "after_motion"):
        if not _seconds(value):
            raise ConfigError(f"{where}.{trigger}: must be a number of seconds >= 0, not {value!r}")
        return float(value), (0, 0)
    if not isinstance(value, Mapping) or set(value) != {"address", "value"}:
        raise ConfigError(f"{where}.when_io: must be {{address = A, value = V}}, not {value!r}")
    address, v = value["address"], value["value"]
    if not isinstance(address, int) or isinstance(address, bool) or address < 0:
        raise ConfigError(f"{where}.when_io.address: must be an IO address, not {address!r}")
    if not isinstance(v, int) or isinstance(v, bool) or not 0 <= v <= 0xFFFF:
        raise ConfigError(f"{where}.when_io.value: must be 0..65535, not {v!r}")
    return 0.0, (address, v)


def _params(
    raw: Mapping[str, object], trigger: str, spec: ActionSpec[ActionTarget], where: str
) -> dict[str, object]:
    """The action's parameters, checked by its declaration (the control API's words)."""
    params: dict[str, object] = {}
    for key, val in raw.items():
        if key in (trigger, "action"):
            continue
        if spec.param(key) is None:
            known = ", ".join(spec.keys) or "none"
            hint = _nearest(key, spec.keys)
            raise ConfigError(
                f"{where}.{key}: unknown key for action {spec.name!r} (its keys: {known}){hint}"
            )
        params[key] = val
    try:
        spec.check_values(params)
        for p in spec.params:
            if p.required and p.name not in params:
                raise ConfigError(f"{where}.{p.name}: is required for action {spec.name!r}")
        spec.check_rules(spec.complete(params))
    except ActionParamError as exc:
        raise ConfigError(f"{where}.{exc}" if exc.key else f"{where}: {exc}") from exc
    return params


@dataclass(frozen=True, slots=True)
class FiredEvent:
    """An event that fired: when (seconds since boot), what, and a refusal if any."""

    t: float
    action: str
    params: Mapping[str, object]
    error: str = ""


Action = Callable[[ScenarioEvent], None]


def scenario_loader(actions: Sequence[ActionSpec[ActionTarget]] = CONTROL_ACTIONS) -> Call:
    """Loading a scenario whose events may carry ``actions``: the scenario action's call."""

    def load(target: ActionTarget, p: Params) -> None:
        events = {"events": p["events"]}
        target.load_scenario(parse_scenario(events, source="POST /api/scenario", actions=actions))

    return load


def scenario_action(
    actions: Sequence[ActionSpec[ActionTarget]] = CONTROL_ACTIONS,
) -> ActionSpec[ActionTarget]:
    """The action that loads a scenario (``POST /api/scenario``), its events taking any of
    ``actions``. Declared here, over the declarations it is given, so that the actions'
    module never needs this one."""
    return ActionSpec(
        "scenario",
        "/api/scenario",
        "Run timed events (same keys as a scenario file); replaces events not fired yet.",
        scenario_loader(actions),
        (
            Param(
                "events", "tables", "timed events, the keys of a scenario file's [[events]] tables"
            ),
        ),
        tag="safety",
        in_scenarios=False,
    )


def with_scenario_of(
    actions: Sequence[ActionSpec[ActionTarget]],
) -> tuple[ActionSpec[ActionTarget], ...]:
    """A surface's whole action list: ``actions`` and the scenario loader, whose events
    take every one of them (an action named "scenario" among them is bound to them in
    its place; otherwise the loader comes last, as in the OpenAPI document)."""
    if any(spec.name == "scenario" for spec in actions):
        return tuple(
            replace(spec, call=scenario_loader(actions)) if spec.name == "scenario" else spec
            for spec in actions
        )
    return (*actions, scenario_action(actions))


def perform(target: ActionTarget, event: ScenarioEvent) -> None:
    """Carry out one event's action (a ValueError, ActionRefusedError, when the target
    refuses it now)."""
    spec = event.spec if event.spec is not None else ACTIONS.get(event.action)
    if spec is None:  # parse_scenario refuses unknown actions
        raise ValueError(f"unknown scenario action {event.action!r}")
    spec.perform(target, event.params)


class ScenarioDriver:
    """Fires a scenario's events from the controller's tick (deterministic in virtual time)."""

    def __init__(
        self,
        scenario: Scenario,
        *,
        perform: Action,
        read_io: Callable[[int], int],
        now_ms: int,
    ) -> None:
        self._pending: list[ScenarioEvent] = list(scenario.events)
        self._perform = perform
        self._read_io = read_io
        self.fired: list[FiredEvent] = []
        self._motion_t0: int | None = None
        """First executed increment of the first trajectory after loading (None: not yet);
        every after_motion event counts from it."""
        self._was_moving = True  # a motion already under way is not "the next trajectory"
        self._loaded_ms = now_ms

    @property
    def done(self) -> bool:
        return not self._pending

    def tick(self, now_ms: int, moved: bool) -> None:
        """One tick; ``moved``: increments were executed this tick."""
        if moved and not self._was_moving and self._motion_t0 is None:
            self._motion_t0 = now_ms
        self._was_moving = moved
        due: list[ScenarioEvent] = []
        for event in self._pending:
            if event.trigger == "at":
                hit = now_ms >= event.seconds * 1000
            elif event.trigger == "after_motion":
                t0 = self._motion_t0
                hit = t0 is not None and now_ms >= t0 + event.seconds * 1000
            else:
                hit = self._read_io(event.io[0]) == event.io[1]
            if hit:
                due.append(event)
        for event in due:
            self._pending.remove(event)
            self._fire(event, now_ms)

    def _fire(self, event: ScenarioEvent, now_ms: int) -> None:
        error = ""
        try:
            self._perform(event)
        except ValueError as exc:
            error = str(exc)
            logger.error("scenario event %d (%s) refused: %s", event.index, event.action, error)
        else:
            logger.warning(
                "scenario event %d at %.3f s: %s %s",
                event.index,
                now_ms / 1000,
                event.action,
                dict(event.params),
            )
        self.fired.append(FiredEvent(now_ms / 1000, event.action, dict(event.params), error))
