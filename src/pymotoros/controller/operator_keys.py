"""The operator's keys on the pendant: E-stop, HOLD, mode, REMOTE, servo, eco, alarms, RESET.

:class:`OperatorKeys` turns each key into the operator-machine event it stands for, at
the controller's time, and keeps the alarm history. It is the operator-panel part of
:class:`~pymotoros.controller.controller.VirtualController`, which delegates to it, and
the :class:`~pymotoros.controller.ports.OperatorPort` the safety functions act through
(read the state, raise an alarm, cut servo power).

It fills its own part of the controller's snapshot (:meth:`OperatorKeys.snapshot`, an
:class:`~pymotoros.controller.values.OperatorSnapshot`), and the declared actions reach
it directly (``target.keys``). So a new key with state of its own is three source files
(docs/architecture.md counts them): its method and state here, filled in
:meth:`OperatorKeys.snapshot`; its field on ``OperatorSnapshot`` in
``controller/values.py``; its ``ActionSpec`` in ``controller/actions.py``, calling
``target.keys``. No facade method, no edit of the controller's ``snapshot()``.
"""

from __future__ import annotations

import logging
from typing import Final

from pymotoros.controller.alarms import Alarm, AlarmHistory
from pymotoros.controller.machine import EstopSource, Event, OperatorMachine, OperatorState
from pymotoros.controller.processes import ControllerClock
from pymotoros.controller.values import OperatorSnapshot
from pymotoros.protocol.constants import PendantMode

logger = logging.getLogger(__name__)

MAX_ALARM_CODE: Final = 9999


class OperatorKeys:
    """The pendant's keys, each one event of the :class:`OperatorMachine`."""

    def __init__(self, machine: OperatorMachine, clock: ControllerClock) -> None:
        self._machine = machine
        self._clock = clock
        self._history = AlarmHistory()
        for alarm in machine.state.alarms:
            self._history.record(alarm)

    def fire(
        self, event: Event, *, alarm: Alarm | None = None, source: EstopSource = EstopSource.PENDANT
    ) -> str | None:
        """``event`` now; the refusal's reason, or None when it was accepted."""
        return self._machine.fire(event, self._clock.time_ms, alarm=alarm, source=source)

    @property
    def state(self) -> OperatorState:
        """The operator state now, frozen."""
        return self._machine.state

    def snapshot(self) -> OperatorSnapshot:
        """The operator state as the pendant shows it, frozen, for the controller's
        snapshot."""
        s = self._machine.state
        return OperatorSnapshot(
            mode=s.mode,
            remote=s.remote,
            servo=s.servo_on,
            estop=s.estopped,
            hold=s.hold,
            alarms=tuple(a.info for a in s.alarms),
            errors=tuple(e.info for e in s.errors),
            eco=s.eco,
        )

    def servo_off(self) -> None:
        """Cut servo power (a safety function's stop; the pendant's servo-off key)."""
        self.fire(Event.SERVO_OFF)

    def alarm_history(self) -> tuple[Alarm, ...]:
        return self._history.entries()

    def alarms_raised(self) -> int:
        """Alarms and operator errors raised since boot (boot alarms included)."""
        return self._history.recorded

    def press_estop(self, pressed: bool, source: EstopSource = EstopSource.PENDANT) -> None:
        """E-stop: cuts servo power and stops the job; raises no alarm."""
        self.fire(Event.PRESS_ESTOP if pressed else Event.RELEASE_ESTOP, source=source)

    def set_hold(self, on: bool) -> None:
        self.fire(Event.HOLD_ON if on else Event.HOLD_OFF)

    def set_mode(self, mode: PendantMode) -> None:
        if not isinstance(mode, PendantMode):
            raise ValueError(f"mode must be a PendantMode, not {mode!r}")
        self.fire(Event.SELECT_PLAY if mode is PendantMode.PLAY else Event.SELECT_TEACH)

    def set_remote(self, on: bool) -> None:
        self.fire(Event.REMOTE_ON if on else Event.REMOTE_OFF)

    def set_servo(self, on: bool) -> None:
        """Servo power request as from the pendant (refused silently while E-stopped or alarmed)."""
        refused = self.fire(Event.REQUEST_SERVO_ON if on else Event.SERVO_OFF)
        if refused:
            logger.info("servo on refused: %s", refused)

    def set_eco(self, on: bool) -> None:
        """Enter eco mode (servo power saved; needs servo on) or leave it (servo power back)."""
        if on:
            refused = self.fire(Event.ENTER_ECO)
            if refused:
                logger.info("eco mode refused: %s", refused)
        else:
            self.fire(Event.WAKE_FROM_ECO)

    def raise_alarm(self, code: int, subcode: int, text: str) -> None:
        self._raise(Event.RAISE_ALARM, "alarm", code, subcode, text)

    def raise_error(self, code: int, subcode: int = 0, text: str = "") -> None:
        """An operator error (50014): refuses motion with 5002 until reset; not an alarm."""
        self._raise(Event.RAISE_ERROR, "error", code, subcode, text)

    def _raise(self, event: Event, kind: str, code: int, subcode: int, text: str) -> None:
        if not 0 <= code <= MAX_ALARM_CODE:
            raise ValueError(f"{kind} code {code} is outside 0..{MAX_ALARM_CODE}")
        alarm = Alarm(code, subcode, text, self._clock.time_ms)
        self._history.record(alarm)
        self.fire(event, alarm=alarm)

    def reset(self) -> None:
        """The pendant's RESET key: clears alarms and errors (their causes are gone)."""
        self.fire(Event.RESET_ALARMS)
        self.fire(Event.CANCEL_ERRORS)
