"""A group's increment queue (200 entries, §5.1–5.2) and its entries.

The tick-by-tick engine queues a segment's entries before computing their pulses: it
knows their number and times from the step grid alone. The pulses of every segment
waiting in the queue are computed when IncMove reaches them: all together, vectorised
(:meth:`IncrementQueue.realise`), or, with a ``compute_front`` callback, the oldest
segment at a time (:meth:`IncrementQueue.due`), so that no tick pays for the whole
queue. Counting, CHECK_QUEUE_CNT and the 200-entry limit see the same queue either way.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator
from typing import NamedTuple, Protocol

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


class LazyEntries(Protocol):
    """A segment whose entries may not be computed yet."""

    @property
    def entries(self) -> list[Increment] | None: ...


class IncrementQueue:
    """The bounded FIFO between AddToIncQueue and IncMove."""

    __slots__ = ("_compute", "_compute_front", "_entries", "_lazy", "_lazy_count")

    def __init__(
        self,
        compute: Callable[[], None] | None = None,
        compute_front: Callable[[], None] | None = None,
    ) -> None:
        self._entries: deque[Increment] = deque()
        self._lazy: deque[tuple[LazyEntries, int, int]] = deque()
        self._lazy_count = 0
        self._compute = compute
        """Computes every segment with queued but uncomputed entries (set by the owner)."""
        self._compute_front = compute_front
        """Computes at least the oldest uncomputed segment, in queue order (optional)."""

    def __len__(self) -> int:
        return len(self._entries) + self._lazy_count

    def __iter__(self) -> Iterator[Increment]:
        self.realise()
        return iter(tuple(self._entries))

    @property
    def count(self) -> int:
        """Entries queued: what CHECK_QUEUE_CNT reports."""
        return len(self._entries) + self._lazy_count

    @property
    def room(self) -> int:
        return QUEUE_SIZE - len(self)

    @property
    def full(self) -> bool:
        return len(self) >= QUEUE_SIZE

    def pop(self) -> Increment:
        """The oldest entry; IndexError when empty."""
        if not self._entries:
            self.realise()
        return self._entries.popleft()

    def add_lazy(self, segment: LazyEntries, start: int, stop: int) -> None:
        """Append entries start … stop − 1 of a segment, computed later if need be."""
        self._lazy.append((segment, start, stop))
        self._lazy_count += stop - start
        self._check()

    def queue_segment(self, segment: LazyEntries, start: int, count: int) -> int:
        """Queue entries ``start`` … of a segment, up to ``count``, as many as fit.

        Returns the index after the last entry queued (``start`` when the queue is
        full). Entries of the segment queued on the previous call are joined into one
        chunk. The AddToIncQueue task calls this every tick, usually for one entry, so
        it touches the fields directly.
        """
        lazy_count = self._lazy_count
        room = QUEUE_SIZE - len(self._entries) - lazy_count
        if room <= 0:
            return start
        stop = count if start + room >= count else start + room
        lazy = self._lazy
        if lazy and lazy[-1][0] is segment:  # extend the chunk queued on the last tick
            lazy[-1] = (segment, lazy[-1][1], stop)
        else:
            lazy.append((segment, start, stop))
        self._lazy_count = lazy_count + stop - start
        return stop

    def due(self) -> deque[Increment]:
        """The computed entries, oldest first, for IncMove to pop from.

        IncMove may join an entry with the next one, so when fewer than two are
        computed, queued entries are computed first: segment by segment from the oldest
        with a ``compute_front`` callback, until two are; otherwise all in one go.
        """
        entries = self._entries
        if len(entries) < 2 and self._lazy:
            if self._compute_front is None:
                self.realise()
            else:
                self._realise_front()
        return entries

    def _realise_front(self) -> None:
        """Move the oldest queued chunks to the computed entries until two are there,
        computing their segments one at a time."""
        entries = self._entries
        lazy = self._lazy
        compute_front = self._compute_front
        while lazy and len(entries) < 2:
            segment, start, stop = lazy[0]
            computed = segment.entries
            if computed is None and compute_front is not None:
                compute_front()
                computed = segment.entries
            if computed is None:
                raise RuntimeError("a queued segment was not computed")
            lazy.popleft()
            self._lazy_count -= stop - start
            entries.extend(computed[start:stop])

    def realise(self) -> None:
        """Compute the pulses of every queued entry."""
        if not self._lazy:
            return
        if self._compute is not None:
            self._compute()
        entries = self._entries
        for segment, start, stop in self._lazy:
            computed = segment.entries
            if computed is None:
                raise RuntimeError("a queued segment was not computed")
            entries.extend(computed[start:stop])
        self._lazy.clear()
        self._lazy_count = 0

    def clear(self) -> None:
        self._entries.clear()
        self._lazy.clear()
        self._lazy_count = 0

    def _check(self) -> None:
        if len(self) > QUEUE_SIZE:
            raise RuntimeError(f"increment queue over {QUEUE_SIZE} entries")
