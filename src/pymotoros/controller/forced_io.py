"""Forcing a signal as the operator simulating the cell (``force_io``).

Signals that belong to the operator state (E-stop inputs, mode, remote, servo, hold,
eco, operating, alarm and error outputs) are forced through the same transition as the
matching pendant key, so the operator state and the IO image never disagree; any other
bit, and the M-registers (1000000 + n), are written directly.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.alarms import AlarmClass
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.machine import EstopSource, Event
from pymotoros.controller.operator_keys import OperatorKeys
from pymotoros.models.controllers import M_REGISTER_BASE
from pymotoros.protocol.constants import PendantMode

FORCED_ALARM_CODE: Final = {
    AlarmClass.MAJOR: 0,
    AlarmClass.MINOR: 4000,
    AlarmClass.USER: 8000,
    AlarmClass.SYSTEM: 9000,
}
"""Alarm numbers used when the operator forces an alarm output on (no alarm text exists)."""

Handler = Callable[[bool], None]


class ForcedSignals:
    """``force(address, value)``: a key's transition for operator signals, a write otherwise."""

    def __init__(self, io: IoImage, keys: OperatorKeys) -> None:
        self._io = io
        self._keys = keys
        self._handlers = self._signal_handlers()

    def force(self, address: int, value: int) -> None:
        """Force a bit or an M-register (ValueError for an address or value out of range)."""
        self._io.check_forcible(address, value)
        if address >= M_REGISTER_BASE:
            self._io.set_mregister(address - M_REGISTER_BASE, value)
            return
        handler = self._handlers.get(address)
        if handler is not None:
            handler(bool(value))
        else:
            self._io.set(address, bool(value))

    def _signal_handlers(self) -> dict[int, Handler]:
        keys = self._keys
        handlers: dict[int, Handler] = {
            signals.ESTOP_EXTERNAL: self._estop(EstopSource.EXTERNAL),
            signals.ESTOP_PENDANT: self._estop(EstopSource.PENDANT),
            signals.ESTOP_CONTROLLER: self._estop(EstopSource.CONTROLLER),
            signals.REMOTE: keys.set_remote,
            signals.PLAY: lambda on: keys.set_mode(PendantMode.PLAY if on else PendantMode.TEACH),
            signals.TEACH: lambda on: keys.set_mode(PendantMode.TEACH if on else PendantMode.PLAY),
            signals.HOLD: keys.set_hold,
            signals.SERVO_ON: keys.set_servo,
            signals.ECO_MODE: keys.set_eco,
            signals.OPERATING: self._operating,
            signals.ERROR: self._error,
        }
        for cls in AlarmClass:
            handlers[cls.address] = self._alarm_output(cls)
        return handlers

    def _estop(self, source: EstopSource) -> Handler:
        return lambda on: self._keys.press_estop(not on, source)

    def _alarm_output(self, cls: AlarmClass) -> Handler:
        def force(on: bool) -> None:
            if on:
                code = FORCED_ALARM_CODE[cls]
                self._keys.raise_alarm(code, 0, f"{cls.name.lower()} alarm forced on {cls.address}")
            else:
                self._keys.fire(Event.RESET_ALARMS)

        return force

    def _operating(self, on: bool) -> None:
        refused = self._keys.fire(Event.START_JOB if on else Event.STOP_JOB)
        if refused:
            raise ValueError(f"cannot start the job: {refused}")

    def _error(self, on: bool) -> None:
        if on:
            self._keys.raise_error(0, 0, "error forced on 50014")
        else:
            self._keys.fire(Event.CANCEL_ERRORS)
