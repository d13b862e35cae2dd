"""Alarms and operator errors: what is active now, and a bounded history.

Yaskawa controllers report alarms on four specific outputs (major, minor, system,
user; reference §2.6) and operator errors on a fifth (50014). Which numbers belong
to which class is not published; :func:`alarm_class` documents the split we use
(see ``docs/fidelity.md``).
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.values import AlarmInfo

HISTORY_LENGTH: Final = 100
"""Alarms and errors kept in the history (the pendant's alarm history holds about as many)."""


class AlarmClass(enum.Enum):
    """Which specific output an alarm sets, and whether it cuts servo power."""

    MAJOR = signals.ALARM_MAJOR
    MINOR = signals.ALARM_MINOR
    SYSTEM = signals.ALARM_SYSTEM
    USER = signals.ALARM_USER

    @property
    def address(self) -> int:
        return int(self.value)

    @property
    def cuts_servo(self) -> bool:
        return self in (AlarmClass.MAJOR, AlarmClass.SYSTEM)


MINOR_FIRST: Final = 4000
USER_FIRST: Final = 8000
SYSTEM_FIRST: Final = 9000


def alarm_class(code: int) -> AlarmClass:
    """Our split of alarm numbers (a modelling choice, see docs/fidelity.md).

    0..3999 major, 4000..7999 minor, 8000..8999 user (MotoPlus applications such as
    MotoROS raise 8000..8004 here), 9000 and above system.
    """
    if code < MINOR_FIRST:
        return AlarmClass.MAJOR
    if code < USER_FIRST:
        return AlarmClass.MINOR
    if code < SYSTEM_FIRST:
        return AlarmClass.USER
    return AlarmClass.SYSTEM


@dataclass(frozen=True, slots=True)
class Alarm:
    """One alarm or operator error, with the controller time it was raised."""

    code: int
    subcode: int
    text: str
    raised_at_ms: int

    @property
    def info(self) -> AlarmInfo:
        return AlarmInfo(self.code, self.subcode, self.text)

    @property
    def alarm_class(self) -> AlarmClass:
        return alarm_class(self.code)


class AlarmHistory:
    """Bounded history of every alarm and error ever raised (oldest dropped first), and
    how many were ever recorded (``GET /metrics``'s ``pymotoros_alarms_total``: a count
    read from the bounded entries would stop at their length between two scrapes)."""

    __slots__ = ("_entries", "recorded")

    def __init__(self, length: int = HISTORY_LENGTH) -> None:
        self._entries: deque[Alarm] = deque(maxlen=length)
        self.recorded = 0
        """Alarms and errors recorded since boot, the dropped ones included."""

    def record(self, alarm: Alarm) -> None:
        self._entries.append(alarm)
        self.recorded += 1

    def entries(self) -> tuple[Alarm, ...]:
        return tuple(self._entries)
