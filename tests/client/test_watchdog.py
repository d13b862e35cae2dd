"""``StallWatchdog``: trips once when the state stream is silent for its bound."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

import pytest

from pymotoros.client.state import RobotState, StateTracker
from pymotoros.client.watchdog import DEFAULT_STATE_STALL_S, StallWatchdog
from pymotoros.testing import twin


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


class _VirtualClock:
    """A client clock that moves only when told to (a virtual time line)."""

    def __init__(self) -> None:
        self.t = 0.0
        self.woken = asyncio.Event()

    def now(self) -> float:
        return self.t

    async def sleep(self, seconds: float) -> None:
        deadline = self.t + max(seconds, 0.0)
        while self.t < deadline:
            self.woken.clear()
            await self.woken.wait()

    def advance(self, seconds: float) -> None:
        self.t += seconds
        self.woken.set()


async def test_on_a_virtual_clock_real_time_does_not_count() -> None:
    """Silence is counted on the client's clock: real seconds with the virtual clock
    still give no trip, virtual seconds do (issue 31, item 3)."""
    tracker = StateTracker()
    clock = _VirtualClock()
    tripped: list[float] = []
    watchdog = StallWatchdog(tracker, 0.05, tripped.append, clock=clock)
    await asyncio.sleep(0.15)  # three bounds of real time, none of virtual time
    assert tripped == []
    clock.advance(0.04)
    await asyncio.sleep(0)
    assert tripped == []
    clock.advance(0.02)
    for _ in range(3):
        await asyncio.sleep(0)
    assert tripped == [pytest.approx(0.06)]
    assert watchdog.tripped_after == tripped[0]
    watchdog.close()
    watchdog.close()


async def test_a_real_pause_longer_than_the_bound_does_not_stop_a_twin_move() -> None:
    """The whole process stops for longer than the bound (here inside a controller tick,
    as a debugger or a loaded CI runner would) during an in-memory move: the state stream
    was never silent in the twin's time, so the move completes."""
    bound_s = 0.1
    async with twin(robot="hc10") as (client, cell):
        client.streamer.state_stall_s = bound_s
        await client.enable()
        paused: list[float] = []

        def pause_once() -> None:
            if not paused and cell.controller.in_motion():
                paused.append(cell.clock.now())
                time.sleep(3 * bound_s)  # the real process, not the twin, stands still

        remove = cell.on_tick(pause_once)
        try:
            result = await client.move_joints([0.4, 0, 0, 0, 0, 0], speed_scale=0.5)
        finally:
            remove()
        assert paused, "the move never ran a tick in motion"
        assert abs(result.final_positions[0] - 0.4) < 1e-3
