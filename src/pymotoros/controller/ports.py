"""The ports through which one part of the controller acts on another, declared once.

Parts are wired when :func:`~pymotoros.controller.assembly.assemble` builds them: each
receives what it acts on as a constructor argument typed with one of these protocols,
and no part assigns an attribute of another after construction (issue 30). So a reader
sees in a constructor's signature everything a part can do to the rest of the
controller, and a new fault reaches the operator state through a port it already has.

- :class:`OperatorPort`: what the cell's safety functions do to the operator state,
  as the real safety unit does through the controller: read it, raise an alarm, cut
  servo power (a category 0 stop). The pendant's keys implement it
  (:class:`~pymotoros.controller.operator_keys.OperatorKeys`).
- :class:`MotionLink`: the motion connections a scenario's ``drop_motion`` cuts, as a
  pulled cable would. The runtime implements it (the motion server's client set) and
  passes it when it builds the controller; the domain layer never imports the runtime.

The FSU's TCP-speed clip, which needs kinematics, is the FSU's own port
(:data:`~pymotoros.controller.safety.fsu.IncrementLimiter`); the controller's
:class:`~pymotoros.controller.tool_point.TcpTracker` provides it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

__all__ = ["AlarmReading", "MotionLink", "OperatorPort", "OperatorReading"]


class AlarmReading(Protocol):
    """An alarm as a safety function reads it (``controller.alarms.Alarm`` is one)."""

    @property
    def code(self) -> int: ...

    @property
    def subcode(self) -> int: ...

    @property
    def text(self) -> str: ...


class OperatorReading(Protocol):
    """What a safety function reads of the operator state (``machine.OperatorState`` is
    one). Declared here, not imported, so that this module stays a leaf."""

    @property
    def alarms(self) -> Sequence[AlarmReading]: ...

    @property
    def hold(self) -> bool: ...

    @property
    def estopped(self) -> bool: ...

    @property
    def servo_on(self) -> bool: ...

    @property
    def drives_powered(self) -> bool: ...


class OperatorPort(Protocol):
    """What a safety function may read of and do to the operator state."""

    @property
    def state(self) -> OperatorReading:
        """The operator state now (alarms, servo power, hold …), frozen."""
        ...

    def raise_alarm(self, code: int, subcode: int, text: str) -> None:
        """Raise a controller alarm: the job stops, motion is refused until a reset."""
        ...

    def servo_off(self) -> None:
        """Cut servo power now (the brakes hold the robot where it stands)."""
        ...


class MotionLink(Protocol):
    """The motion port's open connections, as a pulled cable cuts them."""

    def drop_clients(self) -> None:
        """Close every motion connection now (the server notices as a lost client)."""
        ...
