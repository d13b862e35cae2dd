"""Peripherals: IO that behaves like a device in the cell (a gripper's sensor, a clamp).

Each peripheral drives one input bit from one other bit (usually an output the robot
program writes): the input takes the source's value (or its inverse) ``delay_ms`` after
the source changed, as a gripper's "closed" sensor comes on 150 ms after "close". The
peripherals tick with the controller and act only through the IO image; a pick-and-place
script's IO handshake can be tested against the twin this way.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Sequence

from pymotoros.controller.io_image import IoImage
from pymotoros.controller.values import PeripheralConfig

__all__ = ["MAX_DELAY_MS", "PeripheralConfig", "Peripherals"]

logger = logging.getLogger(__name__)

MAX_DELAY_MS = 60_000
"""A device answering after more than a minute is a broken device, not a slow one."""


class Peripherals:
    """Every peripheral of the cell, one tick at a time."""

    def __init__(self, io: IoImage, configs: Sequence[PeripheralConfig]) -> None:
        self._io = io
        self._configs = tuple(configs)
        self._seen = [io.get(c.follows) for c in self._configs]
        self._due: list[deque[tuple[int, int]]] = [deque() for _ in self._configs]
        for c, seen in zip(self._configs, self._seen, strict=True):
            io.set(c.input, seen ^ int(c.invert))

    @property
    def active(self) -> bool:
        return bool(self._configs)

    def tick(self, now_ms: int) -> None:
        io = self._io
        for i, c in enumerate(self._configs):
            value = io.get(c.follows)
            due = self._due[i]
            if value != self._seen[i]:
                self._seen[i] = value
                due.append((now_ms + c.delay_ms, value ^ int(c.invert)))
            while due and due[0][0] <= now_ms:
                _, new = due.popleft()
                if io.get(c.input) != new:
                    logger.debug("peripheral %s: input %d = %d", c.name, c.input, new)
                    io.set(c.input, new)
