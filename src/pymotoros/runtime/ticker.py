"""The interpolation loop: one controller tick per period, on absolute deadlines.

The deadline of tick *k* is ``start + k × period``; the loop never sleeps "one period
after the work", so the work's duration does not accumulate as drift (STYLE B4).
Simulated time stays exact whatever the wall clock does, because every tick advances
the controller by exactly one period.

asyncio on a general-purpose OS is soft real-time: the loop measures how late each
tick starts (lateness p50/p99/max over the last :data:`LATENESS_WINDOW` ticks), counts
overruns (a tick that started more than a whole period late, i.e. a missed slot) and,
after a stall of more than :data:`RESYNC_PERIODS` periods, restarts the schedule from
*now* instead of running a burst of catch-up ticks. It never logs per tick.

Idle batching (issue 13): waking an event loop 250 times a second costs about 1.6 % of
a core on a small VM whatever wakes it, which is most of an idle twin's cost. When
nothing can observe the controller between ticks (the ``may_batch`` predicate the
owner gives: no client connected, no request in flight), the loop sleeps until the
end of a batch of :data:`IDLE_BATCH_TICKS` periods and then runs the due ticks back to
back: the same ``step()`` calls in the same order, only later in wall time, so the
controller stays deterministic and simulated time exact. Whoever is about to observe
the controller calls :meth:`Ticker.catch_up` first (a TCP accept, an HTTP request),
which runs every tick whose deadline has passed and ends the batch; a waiter of
:meth:`Ticker.wait_ticks` is woken at its tick's deadline, as without batching.

Lateness with batching: a tick run before its batch's wake-up deadline (the last
tick of the batch, or the tick a waiter waits for), by the batch or by a catch-up,
was deferred on purpose: it is counted in ``batched``, not sampled, and never an
overrun. The tick on the wake-up deadline is sampled with the wake-up's lateness
(the time the loop woke minus that deadline, the clock's honest precision; the ~0.1 ms
of deferred ticks run just before it are not added, as nobody can see them), and so is
every tick after it due at that wake-up
(a wake-up later than a period still counts overruns, and a stall beyond
:data:`RESYNC_PERIODS` still resyncs). Deferred ticks are never skipped: a resync
drops only ticks after the batch's wake-up deadline.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

import numpy as np

from pymotoros.runtime.clock import Clock

__all__ = [
    "IDLE_BATCH_TICKS",
    "LATENESS_WINDOW",
    "RESYNC_PERIODS",
    "LatenessStats",
    "TickStats",
    "Ticker",
]

logger = logging.getLogger(__name__)

LATENESS_WINDOW: Final = 15_000
"""Ticks whose lateness feeds p50/p99: 60 s at 4 ms. Bounded memory, recent behaviour."""

RESYNC_PERIODS: Final = 5
"""A tick later than this many periods restarts the schedule from now (no catch-up burst)."""

IDLE_BATCH_TICKS: Final = 25
"""Ticks per batch while nobody can observe the controller: 100 ms at 4 ms, so an idle
twin wakes 10 times a second instead of 250 (the ~1.6 % of a core the wake-ups cost
on this VM becomes ~0.1 %), and a catch-up on an observation runs at most ~25 cheap
idle ticks (~1 us each) back to back."""

STATS_LOG_INTERVAL_S: Final = 60.0
"""How often the loop logs its statistics at INFO (never per tick)."""


@dataclass(frozen=True, slots=True)
class LatenessStats:
    """Lateness of tick starts, milliseconds."""

    p50: float
    p99: float
    max: float


@dataclass(frozen=True, slots=True)
class TickStats:
    """A snapshot of the loop's counters for observers (HTTP API, benchmarks, logs)."""

    period_ms: float
    count: int
    overruns: int
    resyncs: int
    skipped: int
    """Ticks dropped by resyncs: simulated time lags wall time by ``skipped × period``."""
    lateness_ms: LatenessStats
    """Over the last :data:`LATENESS_WINDOW` ticks (or since :meth:`Ticker.reset_stats`)."""
    batched: int = 0
    """Ticks deferred on purpose by idle batching (not sampled, never overruns)."""


def _rank(fraction: float, n: int) -> int:
    """Zero-based nearest-rank index of a percentile among ``n`` samples."""
    return max(1, math.ceil(fraction * n)) - 1


class Ticker:
    """Runs ``step()`` once per ``period`` seconds of ``clock`` time, on absolute deadlines.

    ``may_batch`` (optional) answers whether nothing can observe the controller right
    now; while it does, ticks run in batches of ``batch_ticks`` (see the module's
    docstring). The ticker knows nothing of servers: a fleet driving many controllers
    combines its cells' predicates into one.
    """

    def __init__(
        self,
        step: Callable[[], None],
        period: float,
        clock: Clock,
        *,
        window: int = LATENESS_WINDOW,
        resync_periods: int = RESYNC_PERIODS,
        may_batch: Callable[[], bool] | None = None,
        batch_ticks: int = IDLE_BATCH_TICKS,
    ) -> None:
        if period <= 0:
            raise ValueError(f"period must be positive, got {period}")
        if batch_ticks < 1:
            raise ValueError(f"batch_ticks must be at least 1 (1: no batching), got {batch_ticks}")
        self._may_batch = may_batch
        self._batch_ticks = batch_ticks
        self._step = step
        self.period = period
        self._clock = clock
        self._resync_after = resync_periods * period
        if window < 1:
            raise ValueError(f"window must be at least 1, got {window}")
        # A ring of the latest lateness samples; numpy so that the percentiles of a full
        # window cost ~0.2 ms (a sort of a Python list would hold the loop for 2 ms).
        self._lateness = np.zeros(window, dtype=np.float64)
        self._samples = 0
        self.count = 0
        self.overruns = 0
        self.resyncs = 0
        self.skipped = 0
        self.batched = 0
        self._waiters: list[tuple[int, int, asyncio.Future[None]]] = []
        self._order = itertools.count()
        self._deadline: float | None = None  # of the next tick; None until run() starts
        self._batch_until: float | None = None  # ticks due before this were deferred
        self._nudge: asyncio.Future[None] | None = None
        self._next_stall_log = -math.inf
        self._failure: Exception | None = None  # a tick that failed in catch_up()

    def stats(self) -> TickStats:
        n = min(self._samples, len(self._lateness))
        p50 = p99 = top = 0.0
        if n:
            window = self._lateness[:n]
            k50, k99 = _rank(0.50, n), _rank(0.99, n)
            parted = np.partition(window, (k50, k99))
            p50, p99, top = float(parted[k50]), float(parted[k99]), float(window.max())
        return TickStats(
            period_ms=self.period * 1000.0,
            count=self.count,
            overruns=self.overruns,
            resyncs=self.resyncs,
            skipped=self.skipped,
            lateness_ms=LatenessStats(
                p50=p50 * 1000.0,
                p99=p99 * 1000.0,
                max=top * 1000.0,
            ),
            batched=self.batched,
        )

    def lateness_since(self, mark: int) -> tuple[np.ndarray, int, int]:
        """Lateness samples (s) taken after sample number ``mark``, for a scrape.

        Returns ``(samples, new_mark, lost)``: the samples still in the ring, the mark to
        pass next time and how many were overwritten before being read (more than a
        window between two reads). A ``mark`` beyond the count (after :meth:`reset_stats`)
        reads from the start. Off the hot path: the loop only fills its ring.
        """
        total = self._samples
        if mark > total:
            mark = 0
        size = len(self._lateness)
        fresh = total - mark
        lost = max(0, fresh - size)
        fresh -= lost
        if fresh == 0:
            return self._lateness[:0].copy(), total, lost
        end = total % size
        start = (total - fresh) % size
        if start < end:
            samples = self._lateness[start:end].copy()
        else:
            samples = np.concatenate((self._lateness[start:], self._lateness[:end]))
        return samples, total, lost

    def reset_stats(self) -> None:
        """Forget lateness and counters of overruns (e.g. after start-up, in a benchmark)."""
        self._samples = 0
        self.overruns = 0
        self.resyncs = 0
        self.skipped = 0
        self.batched = 0

    @property
    def next_deadline(self) -> float | None:
        """The deadline of the next tick (clock time), or None while not running."""
        return self._deadline

    @property
    def batching(self) -> bool:
        """True while the loop sleeps through a batch (nobody observing)."""
        return self._batch_until is not None

    def catch_up(self) -> int:
        """Bring the controller up to date before someone observes it; returns the ticks run.

        Runs, synchronously, every tick whose deadline has passed and ends the current
        batch, so the loop asks ``may_batch`` again (a new client makes it tick every
        period). Without a batch in progress it does nothing: the loop is on time.
        """
        if self._batch_until is None or self._deadline is None or self._failure is not None:
            return 0
        try:
            return self._run_due(self._clock.now(), None)
        except Exception as exc:
            # A tick that fails here must stop the loop as it would in run() (the
            # simulator's task group then stops everything), not the caller's request.
            self._failure = exc
            logger.error("a tick failed during a catch-up; stopping the interpolation loop")
            return 0
        finally:
            self._end_batch()

    async def wait_ticks(self, n: int) -> None:
        """Return after ``n`` more ticks have run (for tests and tools; no polling)."""
        if n <= 0:
            return
        self.catch_up()  # count from the up-to-date tick; the loop re-plans its wake-up
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        heapq.heappush(self._waiters, (self.count + n, next(self._order), future))
        await future

    async def run(self) -> None:
        """Tick until cancelled."""
        clock = self._clock
        self._deadline = clock.now()
        next_log = self._deadline + STATS_LOG_INTERVAL_S
        try:
            while True:
                # real time: one tick per turn (the loop yields between late ticks);
                # the end of a batch: every due tick back to back
                self._run_due(clock.now(), 1 if self._batch_until is None else None)
                self._batch_until = None
                if self._deadline >= next_log:
                    next_log = self._deadline + STATS_LOG_INTERVAL_S
                    self._log_stats()
                wake = self._batch_wake()
                if wake is None:
                    await clock.sleep_until(self._deadline)
                else:
                    self._batch_until = wake
                    await self._sleep_or_nudge(wake)
                    if self._failure is not None:
                        raise self._failure
        finally:
            self._batch_until = None
            self._deadline = None

    def _batch_wake(self) -> float | None:
        """The deadline to sleep to if the next ticks may be batched, else None."""
        deadline = self._deadline
        if self._may_batch is None or self._batch_ticks < 2 or deadline is None:
            return None
        if not self._may_batch():
            return None
        ticks = self._batch_ticks
        if self._waiters:  # wake up at the deadline of the tick the first waiter waits for
            ticks = min(ticks, self._waiters[0][0] - self.count)
        if ticks < 2:
            return None
        return deadline + (ticks - 1) * self.period

    async def _sleep_or_nudge(self, wake: float) -> None:
        """Sleep until ``wake``, or until :meth:`catch_up` ends the batch."""
        nudge: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._nudge = nudge
        sleep = asyncio.ensure_future(self._clock.sleep_until(wake))
        try:
            await asyncio.wait((sleep, nudge), return_when=asyncio.FIRST_COMPLETED)
        finally:
            self._nudge = None
            # Not awaited: awaiting the cancelled sleep would swallow a cancellation of
            # this task arriving meanwhile (both raise CancelledError).
            sleep.cancel()
            nudge.cancel()

    def _end_batch(self) -> None:
        self._batch_until = None
        nudge = self._nudge
        if nudge is not None and not nudge.done():
            nudge.set_result(None)

    def _run_due(self, now: float, limit: int | None) -> int:
        """Run the ticks due at ``now`` (at most ``limit``); returns how many ran."""
        period = self.period
        clock = self._clock
        ran = 0
        deadline = self._deadline
        if deadline is None:
            return 0
        while deadline <= now and (limit is None or ran < limit):
            if self._batch_until is not None and deadline < self._batch_until:
                self.batched += 1  # deferred on purpose: not late, not sampled
            else:
                # At the end of a batch, lateness is the loop's wake-up (``now``), not
                # the moment after the deferred ticks before it, which nobody observes.
                late = (now if self._batch_until is not None else clock.now()) - deadline
                if late > self._resync_after:
                    # A stall (debugger, swapped-out process, suspended VM): skip the
                    # missed slots rather than bursting through them.
                    missed = int(late / period)
                    self.resyncs += 1
                    self.overruns += 1
                    self.skipped += missed
                    deadline += missed * period
                    self._log_stall(late, missed, deadline)
                    late = clock.now() - deadline
                elif late > period:
                    self.overruns += 1
                self._lateness[self._samples % len(self._lateness)] = late
                self._samples += 1
            self._step()
            self.count += 1
            ran += 1
            deadline += period
            self._deadline = deadline
            if self._waiters:
                self._wake_waiters()
        return ran

    def _log_stall(self, late: float, missed: int, deadline: float) -> None:
        if deadline < self._next_stall_log:  # at most one warning per log interval
            return
        self._next_stall_log = deadline + STATS_LOG_INTERVAL_S
        logger.warning(
            "interpolation loop stalled %.1f ms and skipped %d ticks "
            "(%d stalls so far); simulated time now lags wall time",
            late * 1000.0,
            missed,
            self.resyncs,
        )

    def _wake_waiters(self) -> None:
        while self._waiters and self._waiters[0][0] <= self.count:
            _, _, future = heapq.heappop(self._waiters)
            if not future.done():
                future.set_result(None)

    def _log_stats(self) -> None:
        s = self.stats()
        logger.info(
            "interpolation loop: %d ticks, %d overruns, %d resyncs, lateness p50 %.3f ms "
            "p99 %.3f ms max %.3f ms",
            s.count,
            s.overruns,
            s.resyncs,
            s.lateness_ms.p50,
            s.lateness_ms.p99,
            s.lateness_ms.max,
        )
