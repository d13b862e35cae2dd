"""``StallWatchdog``: trips once when the state stream is silent for its bound."""

from __future__ import annotations

import asyncio
from collections.abc import Callable

import pytest

from pymotoros.client.state import RobotState, StateTracker
from pymotoros.client.watchdog import DEFAULT_STATE_STALL_S, StallWatchdog


async def test_a_silent_stream_trips_it_once_after_the_bound() -> None:
    tracker = StateTracker()
    tripped: list[float] = []
    done = asyncio.Event()

    def on_stall(silence: float) -> None:
        tripped.append(silence)
        done.set()

    loop = asyncio.get_running_loop()
    began = loop.time()
    watchdog = StallWatchdog(tracker, 0.05, on_stall)
    async with asyncio.timeout(5):
        await done.wait()
    assert loop.time() - began >= 0.05
    assert len(tripped) == 1
    assert tripped[0] >= 0.05
    assert watchdog.tripped_after == tripped[0]
    watchdog.close()
    watchdog.close()  # idempotent


async def test_closing_it_removes_its_listener_and_timer() -> None:
    removed: list[bool] = []

    class Source:
        state = RobotState()
        error = None

        async def next_state(self) -> RobotState:
            return self.state

        def add_listener(self, listener: Callable[[RobotState], None]) -> Callable[[], None]:
            return lambda: removed.append(True)

    watchdog = StallWatchdog(Source(), 0.05, lambda _: pytest.fail("closed: must not trip"))
    watchdog.close()
    watchdog.close()
    assert removed == [True]  # removed once, whatever the source's remove does twice
    assert watchdog.tripped_after is None


async def test_the_bound_must_be_positive() -> None:
    with pytest.raises(ValueError, match="> 0 s"):
        StallWatchdog(StateTracker(), 0.0, lambda _: None)
    assert 0 < DEFAULT_STATE_STALL_S <= 1.0
