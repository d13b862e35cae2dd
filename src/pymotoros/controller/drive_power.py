"""What happens to the arm when drive power goes: brake sag, and eco mode after idling.

:class:`DrivePower` models the two effects of servo power the operator machine does
not: the brakes' small sag when power is cut (``servo.brake_sag_pulses``) and the
controller entering eco mode after ``servo.eco_idle_s`` without motion.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.machine import Event

logger = logging.getLogger(__name__)


class DrivePower:
    """Brake sag on each power loss, and the eco-mode idle timer."""

    def __init__(self, ctx: MotoRosContext, *, last_motion_ms: Callable[[], int]) -> None:
        self._ctx = ctx
        self._last_motion_ms = last_motion_ms
        servo = ctx.cell.servo
        self._sag = servo.brake_sag_pulses
        self.eco_idle_ms = None if servo.eco_idle_s is None else servo.eco_idle_s * 1000
        """Eco mode after this much time without motion with servo on (None: never)."""
        self.power_losses = 0

    def brakes_engage(self) -> None:
        """Drive power was cut: the brakes hold each axis, a few pulses off (sag)."""
        self.power_losses += 1
        if not self._sag:
            return
        for servo, axes in zip(self._ctx.servos, self._ctx.axes, strict=True):
            servo.shift(servo.sag_offsets(self._sag, self.power_losses, axes.valid))

    def check_eco_idle(self, now: int) -> None:
        """Eco mode after the configured idle time with servo on (checked every 10 ms)."""
        idle_ms = self.eco_idle_ms
        machine = self._ctx.machine
        s = machine.state
        if idle_ms is None or not s.servo_on or s.eco:
            return
        if now - self._last_motion_ms() >= idle_ms and now - s.servo_ready_at_ms >= idle_ms:
            logger.info("eco mode: no motion for %d s", idle_ms // 1000)
            machine.fire(Event.ENTER_ECO, now)
