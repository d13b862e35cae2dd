"""Where the runtime gets its time from.

Every wait in the runtime goes through a :class:`Clock`: ``now()`` and
``sleep_until(deadline)`` on an absolute, monotonic time line in seconds. The
simulator uses :class:`LoopClock` (the event loop's monotonic clock); tests use a
:class:`ManualClock`, on which time moves only when the test moves it, either step by
step with :meth:`ManualClock.advance` or as fast as the loop can go with
:meth:`ManualClock.run_virtual_time` (a 30 s trajectory then runs in well under a
second, the interpolation loop ticking back to back).
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
from typing import Final, Protocol

__all__ = ["PRECISE_SPIN_S", "Clock", "LoopClock", "ManualClock"]


class Clock(Protocol):
    """A monotonic time source with absolute-deadline sleeps."""

    def now(self) -> float:
        """Monotonic time in seconds."""
        ...

    async def sleep_until(self, deadline: float) -> None:
        """Return once ``now() >= deadline`` (at once, after one loop turn, if it already is)."""
        ...


PRECISE_SPIN_S: Final = 0.001
"""The selector waits in whole milliseconds, rounded up (epoll), so a timer fires up to
1 ms late. A precise clock sets its timer this much early and yields to the loop
(``sleep(0)``, other tasks and I/O keep running) until the deadline."""


class LoopClock:
    """Real time: the running event loop's monotonic clock.

    ``spin`` > 0 makes :meth:`sleep_until` precise to a few tens of microseconds
    instead of up to a millisecond late, at the price of keeping the loop busy for
    the last ``spin`` seconds before each deadline (about a quarter of a core for a
    4 ms loop with the default :data:`PRECISE_SPIN_S`). The interpolation loop uses
    it; everything else does not need it.
    """

    def __init__(self, *, spin: float = 0.0) -> None:
        if spin < 0:
            raise ValueError(f"spin must be >= 0, got {spin}")
        self.spin = spin

    def now(self) -> float:
        return asyncio.get_running_loop().time()

    async def sleep_until(self, deadline: float) -> None:
        loop = asyncio.get_running_loop()
        wake = deadline - self.spin
        if wake > loop.time():
            # call_at on the absolute deadline: asyncio.sleep(delay) would recompute the
            # delay from a later now() and add the scheduling latency.
            future: asyncio.Future[None] = loop.create_future()
            handle = loop.call_at(wake, _resolve, future)
            try:
                await future
            finally:
                handle.cancel()
        await asyncio.sleep(0)
        while loop.time() < deadline:  # noqa: ASYNC110 - the precise last stretch, by design
            await asyncio.sleep(0)


def _resolve(future: asyncio.Future[None]) -> None:
    if not future.done():
        future.set_result(None)


class ManualClock:
    """Virtual time for tests: it moves only when told to.

    Sleepers are kept in a heap of ``(deadline, order, future)``; :meth:`advance` wakes
    them in deadline order (ties in the order they went to sleep), so a run is the same
    every time.
    """

    def __init__(self, start: float = 0.0) -> None:
        self._now = start
        self._sleepers: list[tuple[float, int, asyncio.Future[None]]] = []
        self._order = itertools.count()

    def now(self) -> float:
        return self._now

    @property
    def sleepers(self) -> int:
        """Tasks currently waiting on this clock."""
        return sum(1 for _, _, f in self._sleepers if not f.done())

    @property
    def next_deadline(self) -> float | None:
        """The earliest deadline anyone is waiting for, or None."""
        self._drop_cancelled()
        return self._sleepers[0][0] if self._sleepers else None

    async def sleep_until(self, deadline: float) -> None:
        if deadline <= self._now:
            await asyncio.sleep(0)
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        heapq.heappush(self._sleepers, (deadline, next(self._order), future))
        await future

    def advance(self, seconds: float) -> None:
        """Move time forward and wake, in deadline order, everyone whose deadline has come."""
        if seconds < 0:
            raise ValueError(f"time cannot go backwards (advance by {seconds} s)")
        self.advance_to(self._now + seconds)

    def advance_to(self, when: float) -> None:
        """Move time forward to ``when`` (absolute) and wake the sleepers that are due."""
        if when < self._now:
            raise ValueError(f"time cannot go backwards ({when} < {self._now})")
        self._now = when
        while self._sleepers and self._sleepers[0][0] <= when:
            _, _, future = heapq.heappop(self._sleepers)
            if not future.done():
                future.set_result(None)

    def _drop_cancelled(self) -> None:
        while self._sleepers and self._sleepers[0][2].done():
            heapq.heappop(self._sleepers)

    async def run_virtual_time(self, *, settle_turns: int = 8) -> None:
        """Drive time as fast as possible until cancelled.

        Let the loop run ``settle_turns`` turns (so tasks woken by I/O or by the last
        jump get to run), then jump straight to the earliest deadline. With the ticker
        as a sleeper this runs the interpolation loop back to back. Run it as a task
        and cancel it when done.
        """
        while True:
            for _ in range(settle_turns):
                await asyncio.sleep(0)
            deadline = self.next_deadline
            if deadline is not None:
                self.advance_to(max(deadline, self._now))
