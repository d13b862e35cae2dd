"""The operator state of the controller, and every change to it, as one transition table.

The state (:class:`OperatorState`) is a frozen value: pendant mode, remote, servo power,
E-stop, hold, energy-saving (eco) mode, alarms, errors and whether a job is playing
back. It changes only through :meth:`OperatorMachine.fire`, which looks the event up
in :data:`TRANSITIONS`: each entry lists named guards (all must hold, else the event
is refused with the guard's reason) and one pure effect function.

Consequences that happen on a real controller in the same instant are part of the
effect: E-stop cuts servo power and stops the job; hold, TEACH and servo off stop the
job; a major or system alarm cuts servo power and every alarm stops the job
(reference §3.6: "This covers E-stop (servo drops), hold (operating drops) …").

After every change the specific outputs and control-status bits that the state
implies (reference §2.6) are written to the IO image by :func:`sync_io`, and
observers get the old and the new frozen state.
"""

from __future__ import annotations

import enum
import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.alarms import Alarm, AlarmClass
from pymotoros.controller.io_image import IoImage
from pymotoros.protocol.constants import PendantMode

logger = logging.getLogger(__name__)


class ServoPower(enum.Enum):
    OFF = "off"
    SWITCHING_ON = "switching on"
    """Requested; 50073 rises when the servo-on delay has passed."""
    ON = "on"


class EstopSource(enum.Enum):
    """The three E-stop chains; each has a control-status input that reads 1 while released."""

    EXTERNAL = signals.ESTOP_EXTERNAL
    PENDANT = signals.ESTOP_PENDANT
    CONTROLLER = signals.ESTOP_CONTROLLER


@dataclass(frozen=True, slots=True)
class OperatorState:
    """Everything an operator can see on the pendant, as one immutable value."""

    mode: PendantMode = PendantMode.PLAY
    remote: bool = True
    servo: ServoPower = ServoPower.OFF
    servo_ready_at_ms: int = 0
    estop: frozenset[EstopSource] = frozenset()
    hold: bool = False
    eco: bool = False
    eco_wake_at_ms: int | None = None
    """Set while the controller leaves eco mode on its own (a motion command arrived)."""
    alarms: tuple[Alarm, ...] = ()
    errors: tuple[Alarm, ...] = ()
    job_running: bool = False
    """A job is playing back: the 'operating' output 50070."""

    @property
    def servo_on(self) -> bool:
        return self.servo is ServoPower.ON

    @property
    def estopped(self) -> bool:
        return bool(self.estop)

    @property
    def drives_powered(self) -> bool:
        return self.servo_on and not self.eco


class Event(enum.Enum):
    """Everything that can change the operator state."""

    PRESS_ESTOP = "press E-stop"
    RELEASE_ESTOP = "release E-stop"
    HOLD_ON = "hold on"
    HOLD_OFF = "hold off"
    SELECT_TEACH = "select TEACH"
    SELECT_PLAY = "select PLAY"
    REMOTE_ON = "remote on"
    REMOTE_OFF = "remote off"
    REQUEST_SERVO_ON = "request servo on"
    SERVO_POWER_READY = "servo power ready"
    SERVO_OFF = "servo off"
    RAISE_ALARM = "raise alarm"
    RESET_ALARMS = "reset alarms"
    RAISE_ERROR = "raise error"
    CANCEL_ERRORS = "cancel errors"
    ENTER_ECO = "enter eco mode"
    WAKE_FROM_ECO = "wake from eco mode"
    ECO_WOKEN = "eco mode left"
    START_JOB = "start job"
    END_JOB = "job reached END"
    STOP_JOB = "stop job"


@dataclass(frozen=True, slots=True)
class EventArgs:
    """What an event carries besides its name."""

    now_ms: int
    servo_on_delay_ms: int = 0
    alarm: Alarm | None = None
    source: EstopSource = EstopSource.PENDANT


@dataclass(frozen=True, slots=True)
class Guard:
    """A named condition an event needs; ``why`` is the refusal when it does not hold."""

    name: str
    holds: Callable[[OperatorState], bool]
    why: str


@dataclass(frozen=True, slots=True)
class Transition:
    guards: tuple[Guard, ...]
    effect: Callable[[OperatorState, EventArgs], OperatorState]
    outcome: str
    """What the effect does, in words (for the generated table in docs/fidelity.md)."""


# ------------------------------------------------------------------------------ guards

NO_ESTOP: Final = Guard("no_estop", lambda s: not s.estop, "an E-stop is pressed")
NO_ALARM: Final = Guard("no_alarm", lambda s: not s.alarms, "an alarm is active")
PLAY_MODE: Final = Guard("play", lambda s: s.mode is PendantMode.PLAY, "not in PLAY mode")
REMOTE_MODE: Final = Guard("remote", lambda s: s.remote, "not in REMOTE mode")
SERVO_IS_ON: Final = Guard("servo_on", lambda s: s.servo_on, "servo power is off")
NOT_HELD: Final = Guard("not_held", lambda s: not s.hold, "HOLD is on")
JOB_NOT_RUNNING: Final = Guard(
    "job_not_running", lambda s: not s.job_running, "a job is already running"
)
SWITCHING_ON: Final = Guard(
    "switching_on",
    lambda s: s.servo is ServoPower.SWITCHING_ON,
    "servo power was not requested",
)
ECO_WAKING: Final = Guard(
    "eco_waking", lambda s: s.eco_wake_at_ms is not None, "not leaving eco mode"
)
IN_ECO: Final = Guard("in_eco", lambda s: s.eco, "not in eco mode")
SERVO_ON_NO_ECO: Final = Guard(
    "servo_on_not_eco",
    lambda s: s.servo_on and not s.eco,
    "eco mode needs servo power on and not already in eco mode",
)

# ------------------------------------------------------------------------------ effects


def _stop_job(s: OperatorState) -> OperatorState:
    return replace(s, job_running=False) if s.job_running else s


def _servo_off(s: OperatorState) -> OperatorState:
    return replace(s, servo=ServoPower.OFF, eco=False, eco_wake_at_ms=None, job_running=False)


def _press_estop(s: OperatorState, a: EventArgs) -> OperatorState:
    return _servo_off(replace(s, estop=s.estop | {a.source}))


def _release_estop(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, estop=s.estop - {a.source})


def _hold_on(s: OperatorState, a: EventArgs) -> OperatorState:
    return _stop_job(replace(s, hold=True))


def _hold_off(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, hold=False)


def _teach(s: OperatorState, a: EventArgs) -> OperatorState:
    return _stop_job(replace(s, mode=PendantMode.TEACH))


def _play(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, mode=PendantMode.PLAY)


def _remote(on: bool) -> Callable[[OperatorState, EventArgs], OperatorState]:
    def effect(s: OperatorState, a: EventArgs) -> OperatorState:
        return replace(s, remote=on)

    return effect


def _request_servo_on(s: OperatorState, a: EventArgs) -> OperatorState:
    if s.servo is not ServoPower.OFF:
        return s
    return replace(
        s, servo=ServoPower.SWITCHING_ON, servo_ready_at_ms=a.now_ms + a.servo_on_delay_ms
    )


def _servo_power_ready(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, servo=ServoPower.ON)


def _servo_off_effect(s: OperatorState, a: EventArgs) -> OperatorState:
    return _servo_off(s)


def _raise_alarm(s: OperatorState, a: EventArgs) -> OperatorState:
    if a.alarm is None:
        raise ValueError("RAISE_ALARM needs an alarm")
    same = any(x.code == a.alarm.code and x.subcode == a.alarm.subcode for x in s.alarms)
    alarms = s.alarms if same else (*s.alarms, a.alarm)
    s = _stop_job(replace(s, alarms=alarms))
    return _servo_off(s) if a.alarm.alarm_class.cuts_servo else s


def _reset_alarms(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, alarms=())


def _raise_error(s: OperatorState, a: EventArgs) -> OperatorState:
    if a.alarm is None:
        raise ValueError("RAISE_ERROR needs an error")
    return replace(s, errors=(*s.errors, a.alarm))


def _cancel_errors(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, errors=())


def _enter_eco(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, eco=True)


def _wake_from_eco(s: OperatorState, a: EventArgs) -> OperatorState:
    if s.eco_wake_at_ms is not None:
        return s
    return replace(s, eco_wake_at_ms=a.now_ms + a.servo_on_delay_ms)


def _eco_woken(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, eco=False, eco_wake_at_ms=None)


def _start_job(s: OperatorState, a: EventArgs) -> OperatorState:
    return replace(s, job_running=True)


def _end_job(s: OperatorState, a: EventArgs) -> OperatorState:
    return _stop_job(s)


TRANSITIONS: Final[Mapping[Event, Transition]] = MappingProxyType(
    {
        Event.PRESS_ESTOP: Transition((), _press_estop, "servo off, job stopped; no alarm"),
        Event.RELEASE_ESTOP: Transition((), _release_estop, "that E-stop chain released"),
        Event.HOLD_ON: Transition((), _hold_on, "hold on, job stopped"),
        Event.HOLD_OFF: Transition((), _hold_off, "hold off (the job stays stopped)"),
        Event.SELECT_TEACH: Transition((), _teach, "TEACH, job stopped"),
        Event.SELECT_PLAY: Transition((), _play, "PLAY"),
        Event.REMOTE_ON: Transition((), _remote(True), "remote on"),
        Event.REMOTE_OFF: Transition((), _remote(False), "remote off (the job keeps running)"),
        Event.REQUEST_SERVO_ON: Transition(
            (NO_ESTOP, NO_ALARM), _request_servo_on, "servo switching on (delay starts)"
        ),
        Event.SERVO_POWER_READY: Transition(
            (SWITCHING_ON, NO_ESTOP), _servo_power_ready, "servo on (50073)"
        ),
        Event.SERVO_OFF: Transition((), _servo_off_effect, "servo off, eco off, job stopped"),
        Event.RAISE_ALARM: Transition(
            (), _raise_alarm, "alarm active, job stopped; major/system: servo off"
        ),
        Event.RESET_ALARMS: Transition((), _reset_alarms, "no alarm"),
        Event.RAISE_ERROR: Transition((), _raise_error, "operator error shown (50014)"),
        Event.CANCEL_ERRORS: Transition((), _cancel_errors, "no error"),
        Event.ENTER_ECO: Transition((SERVO_ON_NO_ECO,), _enter_eco, "eco mode (50727)"),
        Event.WAKE_FROM_ECO: Transition((IN_ECO,), _wake_from_eco, "leaving eco (delay starts)"),
        Event.ECO_WOKEN: Transition((ECO_WAKING,), _eco_woken, "eco mode off"),
        Event.START_JOB: Transition(
            (
                PLAY_MODE,
                REMOTE_MODE,
                NO_ESTOP,
                NO_ALARM,
                SERVO_IS_ON,
                NOT_HELD,
                JOB_NOT_RUNNING,
            ),
            _start_job,
            "job running (50070)",
        ),
        Event.END_JOB: Transition((), _end_job, "job over"),
        Event.STOP_JOB: Transition((), _end_job, "job stopped"),
    }
)
"""Every change of the operator state: event → (guards, effect)."""

Observer = Callable[[OperatorState, OperatorState, Event], None]


class OperatorMachine:
    """Holds the current :class:`OperatorState` and applies :data:`TRANSITIONS`."""

    __slots__ = ("_io", "_observers", "_state", "next_timer_ms", "servo_on_delay_ms")

    def __init__(
        self,
        initial: OperatorState,
        io: IoImage,
        *,
        servo_on_delay_ms: int,
        observer: Observer | None = None,
    ) -> None:
        """``observer(old, new, event)`` runs after every change (not after a refusal):
        the controller's reaction (brakes, the job runner, its snapshot observers)."""
        self._state = initial
        self._io = io
        self._observers: tuple[Observer, ...] = (observer,) if observer is not None else ()
        self.servo_on_delay_ms = servo_on_delay_ms
        self.next_timer_ms: int | None = None
        """When :meth:`advance` next has something to do (None: nothing timed)."""
        sync_io(initial, io)

    @property
    def state(self) -> OperatorState:
        return self._state

    def fire(
        self,
        event: Event,
        now_ms: int,
        *,
        alarm: Alarm | None = None,
        source: EstopSource = EstopSource.PENDANT,
    ) -> str | None:
        """Apply ``event``; None if applied, else the reason it was refused."""
        transition = TRANSITIONS[event]
        old = self._state
        for guard in transition.guards:
            if not guard.holds(old):
                logger.debug("%s refused: %s", event.value, guard.why)
                return guard.why
        args = EventArgs(now_ms, self.servo_on_delay_ms, alarm, source)
        new = transition.effect(old, args)
        if new != old:
            self._state = new
            self.next_timer_ms = _next_timer(new)
            sync_io(new, self._io)
            logger.debug("%s: %s", event.value, _describe_change(old, new))
            for observer in self._observers:
                observer(old, new, event)
        return None

    def advance(self, now_ms: int) -> None:
        """Fire the timed events that are due (servo power ready, eco mode left)."""
        s = self._state
        if s.servo is ServoPower.SWITCHING_ON and now_ms >= s.servo_ready_at_ms:
            self.fire(Event.SERVO_POWER_READY, now_ms)
        s = self._state
        if s.eco_wake_at_ms is not None and now_ms >= s.eco_wake_at_ms:
            self.fire(Event.ECO_WOKEN, now_ms)


def _next_timer(s: OperatorState) -> int | None:
    times = []
    if s.servo is ServoPower.SWITCHING_ON:
        times.append(s.servo_ready_at_ms)
    if s.eco_wake_at_ms is not None:
        times.append(s.eco_wake_at_ms)
    return min(times) if times else None


def sync_io(s: OperatorState, io: IoImage) -> None:
    """Write the signals the operator state implies (reference §2.6)."""
    classes = {a.alarm_class for a in s.alarms}
    for cls in AlarmClass:
        io.set(cls.address, cls in classes)
    io.set(signals.ERROR, bool(s.errors))
    io.set(signals.PLAY, s.mode is PendantMode.PLAY)
    io.set(signals.TEACH, s.mode is PendantMode.TEACH)
    io.set(signals.REMOTE, s.remote)
    io.set(signals.OPERATING, s.job_running)
    io.set(signals.HOLD, s.hold)
    io.set(signals.SERVO_ON, s.servo_on)
    io.set(signals.ECO_MODE, s.eco)
    for source in EstopSource:
        io.set(source.value, source not in s.estop)


def _describe_change(old: OperatorState, new: OperatorState) -> str:
    changes = [
        f"{name} {getattr(old, name)!s} → {getattr(new, name)!s}"
        for name in ("mode", "remote", "servo", "hold", "eco", "job_running")
        if getattr(old, name) != getattr(new, name)
    ]
    if old.estop != new.estop:
        changes.append(f"E-stop {sorted(e.name for e in new.estop) or 'released'}")
    if old.alarms != new.alarms:
        changes.append(f"alarms {[a.code for a in new.alarms]}")
    if old.errors != new.errors:
        changes.append(f"errors {[a.code for a in new.errors]}")
    return ", ".join(changes) or "no change"


def transition_table() -> str:
    """The transition table as Markdown (docs/fidelity.md embeds it; a test keeps it in sync)."""
    lines = ["| event | guards (all must hold) | new state |", "|---|---|---|"]
    for event, t in TRANSITIONS.items():
        guards = ", ".join(f"{g.name}" for g in t.guards) or "—"
        lines.append(f"| {event.value} | {guards} | {t.outcome} |")
    return "\n".join(lines)
