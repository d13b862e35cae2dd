"""A group's increment queue (200 entries, §5.1–5.2) and its entries."""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Iterator
from typing import NamedTuple

from pymotoros.motion.constants import QUEUE_SIZE, SLOTS


class Increment(NamedTuple):
    """One queue entry: a pulse increment for every slot of a group, at a time.

    Frame (pulse increment) and user frame (0) are the same for every entry MotoROS
    makes, so they are not stored.
    """

    time_ms: int
    """Trajectory time the increment reaches, ms."""
    pulses: tuple[int, ...]
    """8 pulse increments, controller order, 0 where there is no axis."""
    tool: int
    """Tool file the segment was interpolated with (latched at the segment start)."""


ZERO_PULSES: tuple[int, ...] = (0,) * SLOTS


class IncrementQueue:
    """The bounded FIFO between AddToIncQueue and IncMove."""

    __slots__ = ("_entries",)

    def __init__(self) -> None:
        self._entries: deque[Increment] = deque()

    def __len__(self) -> int:
        return len(self._entries)

    def __iter__(self) -> Iterator[Increment]:
        return iter(tuple(self._entries))

    @property
    def count(self) -> int:
        """Entries queued: what CHECK_QUEUE_CNT reports."""
        return len(self._entries)

    @property
    def room(self) -> int:
        return QUEUE_SIZE - len(self._entries)

    @property
    def full(self) -> bool:
        return len(self._entries) >= QUEUE_SIZE

    def peek(self) -> Increment | None:
        return self._entries[0] if self._entries else None

    def pop(self) -> Increment:
        """The oldest entry; IndexError when empty."""
        return self._entries.popleft()

    def extend(self, entries: Iterable[Increment]) -> None:
        """Append entries; the caller respects :attr:`room`."""
        self._entries.extend(entries)
        if len(self._entries) > QUEUE_SIZE:
            raise RuntimeError(f"increment queue over {QUEUE_SIZE} entries")

    def clear(self) -> None:
        self._entries.clear()
