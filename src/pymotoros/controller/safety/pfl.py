"""Power and Force Limiting (PFL): contact and clamping on HC robots.

The PFL function belongs to the controller's safety unit, not to MotoROS. It acts only
through the IO image (PFL stop 81702, PFL escape 81703) and through the commanded
position it retreats along; MotoROS sees it as its monitor sees any PFL signal (the
"PFL during ROS move" latch, the queue clear) and as the incremental-move function
answering PFL_FUNC_BUSY (reference §2.6, §4.1, §4.4).

Sequence of a contact: PFL stop on at once (the next IncMove call is refused, so no
further increment is executed), for ``stop_ms``; then off. A clamping does the same,
then turns PFL escape on and moves the robot back along its last ``retreat_ms`` of
commanded motion, one recorded tick per tick, and turns escape off.
"""

from __future__ import annotations

import collections
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.servo import ServoGroup
from pymotoros.errors import PymotorosError

logger = logging.getLogger(__name__)

PFL_STOP_MS: Final = 500
"""How long PFL stop (81702) stays on after a contact. Yaskawa publishes no figure for
the virtual cell to copy; half a second is what an operator sees on the pendant before
the signal clears (modelling choice, docs/fidelity.md). Configurable per call."""
MAX_RETREAT_MS: Final = 2000
"""The longest retreat after a clamping the twin records history for (2 s of motion:
far beyond the few hundred ms a clamping retreat is on the HC10)."""


def retreat_record_ticks(period_ms: int) -> int:
    """How many ticks of increments each servo keeps for a clamping's retreat (its
    ``record_ticks``, given when a PFL cell's servos are built)."""
    return MAX_RETREAT_MS // period_ms + 1


DEFAULT_RETREAT_MS: Final = 100
"""Retreat after a clamping when the request names none (the seed's example value)."""


class PflRefusedError(PymotorosError, ValueError):
    """A PFL event that the cell cannot produce (no option, standing still, busy).

    Also a ``ValueError``: a scenario event and the HTTP API refuse it as any bad value."""


@dataclass(frozen=True, slots=True)
class PflStatus:
    """What the PFL function is doing, for the control API."""

    enabled: bool
    phase: str
    """"idle", "stop" (81702 on) or "escape" (81703 on, retreating)."""
    events: int
    """Contacts and clampings since boot."""


class PflFunction:
    """The safety unit's PFL function: ticks with the controller, acts through IO and servos."""

    def __init__(
        self,
        io: IoImage,
        servos: Sequence[ServoGroup],
        *,
        enabled: bool,
        why_disabled: str,
        period_ms: int,
    ) -> None:
        self._io = io
        self._servos = tuple(servos)
        self.enabled = enabled
        self._why_disabled = why_disabled
        self._period_ms = period_ms
        # every tick's increment per group, recorded by the servos themselves (cheap: one
        # append per tick) for a clamping's retreat: built to record when the cell has PFL
        recorders = tuple(s.recorder for s in self._servos if s.recorder is not None)
        if enabled and len(recorders) != len(self._servos):
            raise ValueError(
                "PFL needs servos that record their increments: build them with "
                f"record_ticks=retreat_record_ticks({period_ms})"
            )
        self._recorders: tuple[collections.deque[Sequence[int]], ...] = recorders
        self.phase = "idle"
        """"idle", "stop" (81702 on) or "escape" (81703 on, retreating)."""
        self._stop_until_ms = 0
        self._retreat: list[tuple[tuple[int, ...], ...]] = []
        """Per tick of the retreat, per group, the increment that undoes one recorded tick."""
        self._events = 0

    @property
    def status(self) -> PflStatus:
        return PflStatus(self.enabled, self.phase, self._events)

    @property
    def busy(self) -> bool:
        return self.phase != "idle"

    def event(
        self,
        kind: str,
        now_ms: int,
        *,
        moving: bool,
        stop_ms: int = PFL_STOP_MS,
        retreat_ms: int = 0,
    ) -> None:
        """A contact ("contact") or a clamping ("clamping", retreating ``retreat_ms``).

        Raises :class:`PflRefusedError` (a ValueError) when the cell cannot have one now.
        """
        if kind not in ("contact", "clamping"):
            raise PflRefusedError(f"PFL event must be 'contact' or 'clamping', not {kind!r}")
        if not self.enabled:
            raise PflRefusedError(f"no PFL contact is possible: {self._why_disabled}")
        if self.busy:
            raise PflRefusedError(
                f"a PFL {self.phase} is in progress; wait until the PFL signals clear"
            )
        if not moving:
            raise PflRefusedError(
                "the robot stands still: PFL detects a contact only while the robot moves"
            )
        if stop_ms < 0:
            raise PflRefusedError(f"stop_ms must be >= 0, not {stop_ms}")
        if kind == "clamping" and not 0 < retreat_ms <= MAX_RETREAT_MS:
            raise PflRefusedError(f"retreat_ms must be in 1..{MAX_RETREAT_MS}, not {retreat_ms}")
        self._events += 1
        logger.warning("PFL %s: PFL stop on for %d ms", kind, stop_ms)
        self.phase = "stop"
        self._stop_until_ms = now_ms + stop_ms
        self._io.set(signals.PFL_STOP, 1)
        self._retreat = []
        if kind == "clamping":
            ticks = -(-retreat_ms // self._period_ms)
            recorded = [list(r)[-ticks:] for r in self._recorders]
            steps = min(len(r) for r in recorded)
            # newest first: each step undoes one recorded tick of every group
            self._retreat = [
                tuple(tuple(-x for x in r[len(r) - 1 - k]) for r in recorded)
                for k in range(steps)
            ]

    def tick(self, now_ms: int) -> None:
        """One interpolation period of the safety unit (before MotoROS's IncMove)."""
        if not self.enabled:
            return
        phase = self.phase
        if phase == "idle":
            return
        if phase == "stop":
            if now_ms < self._stop_until_ms:
                return
            self._io.set(signals.PFL_STOP, 0)
            if self._retreat:
                logger.info("PFL escape: retreating %d ticks", len(self._retreat))
                self.phase = "escape"
                self._io.set(signals.PFL_ESCAPE, 1)
            else:
                self._end()
            return
        # escape: one recorded tick undone per tick
        step = self._retreat.pop(0)
        for servo, undo in zip(self._servos, step, strict=True):
            servo.apply(undo)
        if not self._retreat:
            self._io.set(signals.PFL_ESCAPE, 0)
            self._end()

    def _end(self) -> None:
        logger.info("PFL signals clear")
        self.phase = "idle"
        for recorder in self._recorders:
            recorder.clear()
