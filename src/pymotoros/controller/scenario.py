"""Fault scenarios: timed operator and safety events, replayed exactly (virtual or real time).

A scenario is a list of events (TOML ``[[events]]`` tables, or the JSON body of
``POST /api/scenario``). Each event has exactly one trigger and one action:

* triggers: ``at`` (seconds after boot), ``after_motion`` (seconds after the first
  executed increment of the next trajectory: the first to start after the scenario is
  loaded; every ``after_motion`` event counts from that instant), ``when_io``
  (``{address, value}``: as soon as the bit or M-register reads that value);
* actions, whose parameters are the keys of the matching control-API body: ``estop``
  (``pressed``), ``hold``/``remote``/``servo``/``eco`` (``on``), ``mode`` (``mode``),
  ``alarm`` (``code``, ``subcode``, ``text``), ``reset``, ``pfl`` (``event``,
  ``retreat_ms``, ``stop_ms``), ``fsu`` (``joint_speed_pct``/``tcp_speed_mm_s``/``off``),
  ``io`` (``address``, ``value``), ``drop_motion``.

:func:`parse_scenario` is pure and refuses a bad scenario naming the event and the key.
:class:`ScenarioDriver` fires the events from the controller's tick, so a run in virtual
time is deterministic.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final, Protocol

from pymotoros.controller.api import PendantMode
from pymotoros.errors import ConfigError
from pymotoros.models.toml_file import read_toml

logger = logging.getLogger(__name__)

TRIGGERS: Final = ("at", "after_motion", "when_io")


@dataclass(frozen=True, slots=True)
class _Param:
    kind: type | tuple[type, ...]
    required: bool = True
    choices: tuple[object, ...] = ()
    lo: float | None = None
    hi: float | None = None


_KIND_NAMES: Final[Mapping[type | tuple[type, ...], str]] = {
    bool: "true or false",
    int: "an integer",
    str: "a string",
    (int, float): "a number",
}
_BOOL = _Param(bool)
ACTIONS: Final[Mapping[str, Mapping[str, _Param]]] = {
    "estop": {"pressed": _BOOL},
    "hold": {"on": _BOOL},
    "remote": {"on": _BOOL},
    "servo": {"on": _BOOL},
    "eco": {"on": _BOOL},
    "mode": {"mode": _Param(str, choices=("teach", "play"))},
    "alarm": {
        "code": _Param(int, lo=0, hi=9999),
        "subcode": _Param(int, required=False, lo=0),
        "text": _Param(str, required=False),
    },
    "reset": {},
    "pfl": {
        "event": _Param(str, choices=("contact", "clamping")),
        "retreat_ms": _Param(int, required=False, lo=1),
        "stop_ms": _Param(int, required=False, lo=0, hi=60_000),
    },
    "fsu": {
        "joint_speed_pct": _Param(int, required=False, lo=1, hi=100),
        "tcp_speed_mm_s": _Param((int, float), required=False, lo=0),
        "off": _Param(bool, required=False),
    },
    "io": {"address": _Param(int, lo=0), "value": _Param(int, lo=0, hi=0xFFFF)},
    "drop_motion": {},
}
"""Every action and its parameters (the keys of the matching control-API body)."""


@dataclass(frozen=True, slots=True)
class ScenarioEvent:
    """One event: a trigger and an action with its parameters."""

    index: int
    trigger: str
    """"at", "after_motion" or "when_io"."""
    seconds: float = 0.0
    """For "at" and "after_motion"."""
    io: tuple[int, int] = (0, 0)
    """(address, value) for "when_io"."""
    action: str = ""
    params: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class Scenario:
    events: tuple[ScenarioEvent, ...]
    source: str = "<scenario>"


def load_scenario(path: str | Path) -> Scenario:
    """Read a scenario TOML file; a mistake raises ConfigError naming the event and key."""
    return parse_scenario(read_toml(path, "scenario file"), source=str(path))


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def parse_scenario(data: Mapping[str, object], *, source: str = "<scenario>") -> Scenario:
    """Validate a parsed scenario ({"events": [...]}); refuse anything unknown or wrong."""
    if not isinstance(data, Mapping):
        raise ConfigError(f"{source}: a scenario must be a table with an 'events' array")
    unknown = sorted(set(data) - {"events"})
    if unknown:
        raise ConfigError(f"{source}: {unknown[0]}: unknown key (a scenario has only [[events]])")
    raw = data.get("events")
    if not isinstance(raw, list) or not raw:
        raise ConfigError(f"{source}: events: needs at least one [[events]] table")
    return Scenario(tuple(_event(i, e, source) for i, e in enumerate(raw)), source)


def _event(i: int, raw: object, source: str) -> ScenarioEvent:
    where = f"{source}: events[{i}]"
    if not isinstance(raw, Mapping):
        raise ConfigError(f"{where}: must be a table")
    triggers = [t for t in TRIGGERS if t in raw]
    if len(triggers) != 1:
        found = ", ".join(triggers) or "none"
        raise ConfigError(
            f"{where}: needs exactly one trigger of {', '.join(TRIGGERS)} (found: {found})"
        )
    trigger = triggers[0]
    action = raw.get("action")
    if not isinstance(action, str) or action not in ACTIONS:
        raise ConfigError(f"{where}.action: must be one of {', '.join(ACTIONS)}, not {action!r}")
    where = f"{where} ({action})"
    seconds = 0.0
    io = (0, 0)
    value = raw[trigger]
    if trigger in ("at", "after_motion"):
        if not _number(value) or not math.isfinite(float(value)) or float(value) < 0:
            raise ConfigError(f"{where}.{trigger}: must be a number of seconds >= 0, not {value!r}")
        seconds = float(value)
    else:
        if not isinstance(value, Mapping) or set(value) != {"address", "value"}:
            raise ConfigError(f"{where}.when_io: must be {{address = A, value = V}}, not {value!r}")
        address, v = value["address"], value["value"]
        if not isinstance(address, int) or isinstance(address, bool) or address < 0:
            raise ConfigError(f"{where}.when_io.address: must be an IO address, not {address!r}")
        if not isinstance(v, int) or isinstance(v, bool) or not 0 <= v <= 0xFFFF:
            raise ConfigError(f"{where}.when_io.value: must be 0..65535, not {v!r}")
        io = (address, v)
    spec = ACTIONS[action]
    params: dict[str, object] = {}
    for key, val in raw.items():
        if key in (trigger, "action"):
            continue
        p = spec.get(key)
        if p is None:
            known = ", ".join(spec) or "none"
            raise ConfigError(
                f"{where}.{key}: unknown key for action {action!r} (its keys: {known})"
            )
        ok = isinstance(val, p.kind) and not (isinstance(val, bool) and p.kind is not bool)
        if not ok:
            raise ConfigError(f"{where}.{key}: must be {_KIND_NAMES[p.kind]}, not {val!r}")
        if p.choices and val not in p.choices:
            choices = ", ".join(map(str, p.choices))
            raise ConfigError(f"{where}.{key}: must be one of {choices}, not {val!r}")
        if _number(val) and (
            (p.lo is not None and val < p.lo) or (p.hi is not None and val > p.hi)
        ):
            raise ConfigError(f"{where}.{key}: must lie in {p.lo}..{p.hi}, not {val!r}")
        params[key] = val
    for key, p in spec.items():
        if p.required and key not in params:
            raise ConfigError(f"{where}.{key}: is required for action {action!r}")
    if action == "fsu" and not params:
        raise ConfigError(f"{where}: needs joint_speed_pct, tcp_speed_mm_s or off = true")
    if action == "pfl" and "retreat_ms" in params and params["event"] != "clamping":
        raise ConfigError(f"{where}.retreat_ms: applies to a clamping only")
    return ScenarioEvent(i, trigger, seconds, io, action, params)


@dataclass(frozen=True, slots=True)
class FiredEvent:
    """An event that fired: when (seconds since boot), what, and a refusal if any."""

    t: float
    action: str
    params: Mapping[str, object]
    error: str = ""


Action = Callable[[ScenarioEvent], None]


class ScenarioTarget(Protocol):
    """What a scenario's actions act on: the operator panel and the safety functions."""

    def press_estop(self, pressed: bool) -> None: ...
    def set_hold(self, on: bool) -> None: ...
    def set_remote(self, on: bool) -> None: ...
    def set_servo(self, on: bool) -> None: ...
    def set_eco(self, on: bool) -> None: ...
    def set_mode(self, mode: PendantMode) -> None: ...
    def raise_alarm(self, code: int, subcode: int, text: str) -> None: ...
    def reset(self) -> None: ...
    def force_io(self, address: int, value: int) -> None: ...
    def drop_motion(self) -> None: ...
    def pfl_event(self, event: str, *, retreat_ms: int = ..., stop_ms: int = ...) -> None: ...
    def set_fsu(
        self,
        *,
        joint_speed_pct: int | None = None,
        tcp_speed_mm_s: float | None = None,
        off: bool = False,
    ) -> None: ...


def _int(value: object) -> int:
    if not isinstance(value, int):  # parse_scenario checked it; a bug otherwise
        raise TypeError(f"expected an integer, not {value!r}")
    return value


def perform(target: ScenarioTarget, event: ScenarioEvent) -> None:
    """Carry out one event's action (ValueError when the target refuses it now)."""
    p = event.params
    action = event.action
    if action == "estop":
        target.press_estop(bool(p["pressed"]))
    elif action in ("hold", "remote", "servo", "eco"):
        setter = {
            "hold": target.set_hold,
            "remote": target.set_remote,
            "servo": target.set_servo,
            "eco": target.set_eco,
        }[action]
        setter(bool(p["on"]))
    elif action == "mode":
        target.set_mode(PendantMode(str(p["mode"])))
    elif action == "alarm":
        target.raise_alarm(_int(p["code"]), _int(p.get("subcode", 0)), str(p.get("text", "")))
    elif action == "reset":
        target.reset()
    elif action == "pfl":
        kwargs = {k: _int(v) for k, v in p.items() if k in ("retreat_ms", "stop_ms")}
        target.pfl_event(str(p["event"]), **kwargs)
    elif action == "fsu":
        pct = p.get("joint_speed_pct")
        tcp = p.get("tcp_speed_mm_s")
        target.set_fsu(
            joint_speed_pct=_int(pct) if pct is not None else None,
            tcp_speed_mm_s=float(tcp) if isinstance(tcp, int | float) else None,
            off=bool(p.get("off", False)),
        )
    elif action == "io":
        target.force_io(_int(p["address"]), _int(p["value"]))
    elif action == "drop_motion":
        target.drop_motion()
    else:  # parse_scenario refuses unknown actions; a new one must be added here
        raise ValueError(f"unknown scenario action {action!r}")


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


def fired_as_dicts(fired: Sequence[FiredEvent]) -> list[dict[str, object]]:
    """The ``events`` list of ``GET /api/state``."""
    out: list[dict[str, object]] = []
    for f in fired:
        d: dict[str, object] = {"t": f.t, "action": f.action, **f.params}
        if f.error:
            d["error"] = f.error
        out.append(d)
    return out
