"""ManualClock.call_at: a callback wakes where a sleeping task would, in the same order."""

from __future__ import annotations

import asyncio

from pymotoros.runtime.clock import ManualClock


async def test_callbacks_and_sleepers_run_in_deadline_then_registration_order() -> None:
    clock = ManualClock()
    order: list[str] = []

    async def sleeper(name: str, deadline: float) -> None:
        await clock.sleep_until(deadline)
        order.append(name)

    tasks = [asyncio.create_task(sleeper("task@2 first", 2.0))]
    await asyncio.sleep(0)  # the task is asleep before the callback is registered
    clock.call_at(2.0, lambda: order.append("callback@2"))
    clock.call_at(1.0, lambda: order.append("callback@1"))
    tasks.append(asyncio.create_task(sleeper("task@2 last", 2.0)))
    await asyncio.sleep(0)
    assert clock.sleepers == 2  # callbacks are not tasks
    assert clock.next_deadline == 1.0
    clock.advance_to(1.5)
    await asyncio.sleep(0)
    assert order == ["callback@1"]
    clock.advance_to(2.0)
    await asyncio.gather(*tasks)
    assert order == ["callback@1", "task@2 first", "callback@2", "task@2 last"]


async def test_a_cancelled_callback_never_runs_and_a_due_one_runs_at_once() -> None:
    clock = ManualClock(start=5.0)
    ran: list[str] = []
    handle = clock.call_at(6.0, lambda: ran.append("cancelled"))
    handle.cancel()
    assert clock.next_deadline is None  # dropped from the heap
    clock.call_at(4.0, lambda: ran.append("due"))  # already past: scheduled now
    await asyncio.sleep(0)
    clock.advance_to(7.0)
    await asyncio.sleep(0)
    assert ran == ["due"]
