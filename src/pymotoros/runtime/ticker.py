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

__all__ = ["LATENESS_WINDOW", "RESYNC_PERIODS", "LatenessStats", "TickStats", "Ticker"]

logger = logging.getLogger(__name__)

LATENESS_WINDOW: Final = 15_000
"""Ticks whose lateness feeds p50/p99: 60 s at 4 ms. Bounded memory, recent behaviour."""

RESYNC_PERIODS: Final = 5
"""A tick later than this many periods restarts the schedule from now (no catch-up burst)."""

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


def _rank(fraction: float, n: int) -> int:
    """Zero-based nearest-rank index of a percentile among ``n`` samples."""
    return max(1, math.ceil(fraction * n)) - 1


class Ticker:
    """Runs ``step()`` once per ``period`` seconds of ``clock`` time, on absolute deadlines."""

    def __init__(
        self,
        step: Callable[[], None],
        period: float,
        clock: Clock,
        *,
        window: int = LATENESS_WINDOW,
        resync_periods: int = RESYNC_PERIODS,
    ) -> None:
        if period <= 0:
            raise ValueError(f"period must be positive, got {period}")
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
        self._waiters: list[tuple[int, int, asyncio.Future[None]]] = []
        self._order = itertools.count()

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
        )

    def reset_stats(self) -> None:
        """Forget lateness and counters of overruns (e.g. after start-up, in a benchmark)."""
        self._samples = 0
        self.overruns = 0
        self.resyncs = 0
        self.skipped = 0

    async def wait_ticks(self, n: int) -> None:
        """Return after ``n`` more ticks have run (for tests and tools; no polling)."""
        if n <= 0:
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        heapq.heappush(self._waiters, (self.count + n, next(self._order), future))
        await future

    async def run(self) -> None:
        """Tick until cancelled."""
        clock = self._clock
        period = self.period
        deadline = clock.now()
        next_log = deadline + STATS_LOG_INTERVAL_S
        next_stall_log = deadline
        while True:
            late = clock.now() - deadline
            if late > self._resync_after:
                # A stall (debugger, swapped-out process, suspended VM): skip the missed
                # slots rather than bursting through them.
                missed = int(late / period)
                self.resyncs += 1
                self.overruns += 1
                self.skipped += missed
                deadline += missed * period
                if deadline >= next_stall_log:  # at most one warning per log interval
                    next_stall_log = deadline + STATS_LOG_INTERVAL_S
                    logger.warning(
                        "interpolation loop stalled %.1f ms and skipped %d ticks "
                        "(%d stalls so far); simulated time now lags wall time",
                        late * 1000.0,
                        missed,
                        self.resyncs,
                    )
                late = clock.now() - deadline
            elif late > period:
                self.overruns += 1
            self._lateness[self._samples % len(self._lateness)] = late
            self._samples += 1
            self._step()
            self.count += 1
            if self._waiters:
                self._wake_waiters()
            deadline += period
            if deadline >= next_log:
                next_log = deadline + STATS_LOG_INTERVAL_S
                self._log_stats()
            await clock.sleep_until(deadline)

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
