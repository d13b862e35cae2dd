"""ThreadClock and TimerFdClock wake sleepers never before their deadline, in order,
survive cancelled sleepers and release what they hold (issue 13, item 2). Punctuality
is a benchmark (bench/bench_clock.py), not a test."""

from __future__ import annotations

import asyncio
import contextlib
import os
import threading

import pytest

from pymotoros.runtime.clock import ThreadClock, TimerFdClock
from pymotoros.runtime.ticker import Ticker

from .support import running

PERIOD_S = 0.004
"""The interpolation period of the controllers (YRC1000)."""

SETUP_S = 0.2
"""Time allowed for every sleeper to go to sleep before the first deadline (a loaded
machine may take milliseconds; a deadline already past returns at once, out of order)."""


async def _six_sleepers_wake_in_order_never_early(clock: ThreadClock | TimerFdClock) -> None:
    """Six sleepers 2 ms apart, put to sleep last first: each wakes at or after its
    deadline, in the order of the deadlines."""
    woke: list[tuple[int, float]] = []
    start = clock.now()

    async def sleeper(k: int) -> None:
        deadline = start + SETUP_S + 0.002 * k
        await clock.sleep_until(deadline)
        woke.append((k, clock.now() - deadline))

    async with asyncio.timeout(5.0):
        await asyncio.gather(*(sleeper(k) for k in reversed(range(6))))
    assert [k for k, _ in woke] == list(range(6))
    assert all(late >= 0.0 for _, late in woke), woke


async def test_sleepers_wake_at_or_after_their_deadlines_in_order() -> None:
    await _six_sleepers_wake_in_order_never_early(ThreadClock())


async def test_a_past_deadline_returns_after_one_loop_turn() -> None:
    clock = ThreadClock()
    async with asyncio.timeout(1.0):
        await clock.sleep_until(clock.now() - 1.0)


async def test_cancelled_sleepers_do_not_disturb_the_others() -> None:
    clock = ThreadClock()
    doomed = asyncio.create_task(clock.sleep_until(clock.now() + 0.001))
    await asyncio.sleep(0)
    doomed.cancel()
    async with asyncio.timeout(5.0):
        await clock.sleep_until(clock.now() + 0.003)
    assert doomed.cancelled()


async def test_a_ticker_on_the_thread_clock_counts_ticks() -> None:
    ticks: list[int] = []
    ticker = Ticker(lambda: ticks.append(1), PERIOD_S, ThreadClock())
    async with running(ticker), asyncio.timeout(10.0):
        await ticker.wait_ticks(50)
    assert len(ticks) >= 50
    assert ticker.stats().lateness_ms.p50 >= 0.0


def test_sleepers_on_two_loops_share_the_thread() -> None:
    """Two event loops in two threads (as two cells would if ever run that way)."""
    results: list[bool] = []

    def run() -> None:
        async def main() -> bool:
            clock = ThreadClock()
            deadline = clock.now() + 0.005
            await clock.sleep_until(deadline)
            return clock.now() >= deadline

        results.append(asyncio.run(main()))

    threads = [threading.Thread(target=run) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=10.0)
    assert results == [True, True]


needs_timerfd = pytest.mark.skipif(not TimerFdClock.available(), reason="Linux timerfd only")


@needs_timerfd
async def test_timerfd_sleepers_wake_in_order_never_early() -> None:
    clock = TimerFdClock()
    await _six_sleepers_wake_in_order_never_early(clock)
    clock.close()


@needs_timerfd
async def test_timerfd_is_released_when_the_last_sleeper_is_cancelled() -> None:
    clock = TimerFdClock()
    before = len(os.listdir("/proc/self/fd"))
    task = asyncio.create_task(clock.sleep_until(clock.now() + 10.0))
    await asyncio.sleep(0)
    assert len(os.listdir("/proc/self/fd")) == before + 1
    task.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await task
    assert len(os.listdir("/proc/self/fd")) == before
    async with asyncio.timeout(5.0):  # and it reopens
        await clock.sleep_until(clock.now() + 0.002)
    clock.close()
    assert len(os.listdir("/proc/self/fd")) == before


@needs_timerfd
async def test_a_ticker_on_the_timerfd_clock_counts_ticks() -> None:
    ticker = Ticker(lambda: None, PERIOD_S, TimerFdClock())
    async with running(ticker), asyncio.timeout(10.0):
        await ticker.wait_ticks(50)
    assert ticker.count >= 50


def test_one_timerfd_clock_serves_one_loop() -> None:
    if not TimerFdClock.available():
        pytest.skip("Linux timerfd only")
    clock = TimerFdClock()

    async def nap() -> None:
        await clock.sleep_until(clock.now() + 0.002)

    async def main() -> None:
        task = asyncio.create_task(nap())
        await asyncio.sleep(0)
        await task
        return None

    asyncio.run(main())
    with pytest.raises(RuntimeError, match="one event loop"):
        asyncio.run(nap())
    clock.close()
