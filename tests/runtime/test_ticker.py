"""The interpolation loop's deadline maths, overruns and resync, on a manual clock."""

from __future__ import annotations

import asyncio
import contextlib
import time

import pytest

from pymotoros.runtime.clock import LoopClock, ManualClock
from pymotoros.runtime.ticker import RESYNC_PERIODS, Ticker

from .support import running, settle

PERIOD = 0.004


class Recorder:
    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock
        self.times: list[float] = []

    def __call__(self) -> None:
        self.times.append(self.clock.now())


async def test_manual_clock_wakes_sleepers_in_deadline_order() -> None:
    clock = ManualClock(start=10.0)
    woke: list[str] = []

    async def sleeper(name: str, deadline: float) -> None:
        await clock.sleep_until(deadline)
        woke.append(name)

    async with asyncio.TaskGroup() as tg:
        tg.create_task(sleeper("late", 10.3))
        tg.create_task(sleeper("early", 10.1))
        tg.create_task(sleeper("never-yet", 11.0))
        await settle()
        assert clock.sleepers == 3
        assert clock.next_deadline == pytest.approx(10.1)
        clock.advance(0.5)
        await settle()
        assert woke == ["early", "late"]
        clock.advance_to(11.0)
    assert woke == ["early", "late", "never-yet"]
    with pytest.raises(ValueError, match="backwards"):
        clock.advance(-1.0)


async def test_manual_clock_past_deadline_returns_at_once() -> None:
    clock = ManualClock(start=5.0)
    async with asyncio.timeout(1.0):
        await clock.sleep_until(4.0)
    assert clock.sleepers == 0


def recorded_ticker() -> tuple[ManualClock, Recorder, Ticker]:
    """A ticker on a manual clock whose step records the clock's time of every tick."""
    clock = ManualClock()
    rec = Recorder(clock)
    return clock, rec, Ticker(rec, PERIOD, clock)


async def test_ticks_land_on_absolute_deadlines() -> None:
    clock, rec, ticker = recorded_ticker()
    async with running(ticker):
        for _ in range(10):
            clock.advance(PERIOD)
            await settle()
    assert len(rec.times) == 11  # the first tick runs at start, then one per period
    assert rec.times == pytest.approx([k * PERIOD for k in range(11)])
    stats = ticker.stats()
    assert stats.count == 11
    assert stats.overruns == 0
    assert stats.lateness_ms.max == pytest.approx(0.0, abs=1e-9)


async def test_late_wakeups_do_not_drift_the_schedule() -> None:
    clock, _rec, ticker = recorded_ticker()
    async with running(ticker):
        for _ in range(5):
            clock.advance(PERIOD + 0.001)  # each wake-up 1 ms late
            await settle()
    # Five late wake-ups of 1 ms accumulate 5 ms of wall time, i.e. more than a period:
    # the absolute schedule runs the missed tick back to back instead of drifting.
    assert ticker.count == 7
    late = ticker.stats().lateness_ms
    assert late.max == pytest.approx(4.0, abs=1e-6)
    assert late.p50 == pytest.approx(1.0, abs=1e-6)  # lateness 0,1,2,3,4,0,1 ms
    assert ticker.overruns == 0


async def test_small_stall_catches_up_and_counts_overruns() -> None:
    clock, _rec, ticker = recorded_ticker()
    async with running(ticker):
        clock.advance(3 * PERIOD + 0.001)  # three deadlines missed, below the resync limit
        await settle()
    assert ticker.count == 1 + 3
    assert ticker.resyncs == 0
    assert ticker.overruns == 2  # the ticks that started more than a whole period late


async def test_large_stall_resyncs_instead_of_bursting() -> None:
    clock, rec, ticker = recorded_ticker()
    stall = (RESYNC_PERIODS + 20) * PERIOD + 0.0005
    async with running(ticker):
        clock.advance(stall)
        await settle()
        assert ticker.count == 2  # one tick after the stall, no burst of 25
        assert ticker.resyncs == 1
        # the deadlines 4 ms .. 96 ms were skipped; the one at 100 ms ran (0.5 ms late)
        assert ticker.skipped == RESYNC_PERIODS + 19
        assert ticker.stats().lateness_ms.max == pytest.approx(0.5, abs=1e-6)
        clock.advance(PERIOD)
        await settle()
    assert ticker.count == 3
    # after the resync the schedule continues from the stall, one period apart
    assert rec.times[2] - rec.times[1] == pytest.approx(PERIOD)


async def test_lateness_window_is_bounded_and_recent() -> None:
    clock = ManualClock()
    ticker = Ticker(lambda: None, PERIOD, clock, window=8)
    async with running(ticker):
        clock.advance(PERIOD + 0.002)  # one tick 2 ms late
        await settle()
        assert ticker.stats().lateness_ms.max == pytest.approx(2.0, abs=1e-6)
        for _ in range(50):
            deadline = clock.next_deadline
            assert deadline is not None
            clock.advance_to(deadline)  # punctual again: exactly on each deadline
            await settle()
    assert ticker.count == 52
    assert len(ticker._lateness) == 8
    # the late tick has left the 8-sample window: only recent, punctual ticks remain
    assert ticker.stats().lateness_ms.max == pytest.approx(0.0, abs=1e-9)
    ticker.reset_stats()
    assert ticker.stats().lateness_ms.p99 == 0.0


async def test_wait_ticks_returns_after_n_ticks() -> None:
    clock = ManualClock()
    ticker = Ticker(lambda: None, PERIOD, clock)
    async with running(ticker):
        waiter = asyncio.create_task(ticker.wait_ticks(3))
        for _ in range(2):
            clock.advance(PERIOD)
            await settle()
        assert not waiter.done()
        clock.advance(PERIOD)
        async with asyncio.timeout(1.0):
            await waiter
    assert ticker.count == 4


async def test_virtual_time_runs_much_faster_than_real_time() -> None:
    clock = ManualClock()
    ticker = Ticker(lambda: None, PERIOD, clock)
    started = time.process_time()  # CPU time: a loaded runner does not stretch it
    async with running(ticker):
        driver = asyncio.create_task(clock.run_virtual_time())
        try:
            async with asyncio.timeout(10.0):
                await ticker.wait_ticks(2500)  # 10 s of controller time
        finally:
            driver.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await driver
    assert clock.now() == pytest.approx(2500 * PERIOD, rel=1e-3)
    assert time.process_time() - started < 5.0  # 10 s of controller time in < 5 s of work


async def test_loop_clock_keeps_period_on_real_time() -> None:
    clock = LoopClock()
    ticker = Ticker(lambda: None, PERIOD, clock)
    loop = asyncio.get_running_loop()
    async with running(ticker):
        start = loop.time()
        async with asyncio.timeout(5.0):
            await ticker.wait_ticks(50)
        elapsed = loop.time() - start
        due = (ticker.count + ticker.skipped) * PERIOD  # read with no await in between
    # 50 ticks take at least 200 ms of real time: never early ...
    assert elapsed >= 50 * PERIOD - 0.005
    # ... and a stalled machine makes the ticker skip deadlines, not drift: ticks run plus
    # deadlines skipped account for the real time that passed, however long that was, up
    # to the lag it may carry before it resyncs (a load-proof "200 ms, plus stalls")
    lag = (RESYNC_PERIODS + 1) * PERIOD
    assert elapsed - lag <= due <= elapsed + PERIOD, (elapsed, ticker.count, ticker.skipped)
