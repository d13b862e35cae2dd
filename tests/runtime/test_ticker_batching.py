"""Idle batching (issue 13): ticks run in batches while nobody can observe the controller.

On a manual clock, time moves in exact periods, so every expectation below is exact:
which ticks run when, that a catch-up brings the count to exactly the deadlines passed,
that a waiter still wakes on its tick's deadline, and that a batched controller is, at
every observation, the same as one ticked in real time. Then, on real ports: the HTTP
API and a TCP client see an up-to-date controller after an idle stretch, and a
ROS-driver-like session right after idle gets the same answers as on an unbatched twin.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.scenario import parse_scenario
from pymotoros.protocol.constants import MotionCommand, Port
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionCtrl, WireMessage
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig
from pymotoros.runtime.clock import ManualClock
from pymotoros.runtime.ticker import IDLE_BATCH_TICKS, RESYNC_PERIODS, Ticker

from .peer import Peer
from .support import LOCAL

PERIOD = 0.004
SETTLE_TURNS = 10
"""Loop turns after each step of virtual time: enough for woken tasks (and loopback
I/O already in the socket buffers) to run."""


async def settle() -> None:
    for _ in range(SETTLE_TURNS):
        await asyncio.sleep(0)


class Observed:
    """A ``may_batch`` predicate the test switches."""

    def __init__(self) -> None:
        self.observed = False

    def __call__(self) -> bool:
        return not self.observed


class Recorder:
    """The step: records (tick index, clock time) of every call."""

    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock
        self.calls: list[tuple[int, float]] = []

    def __call__(self) -> None:
        self.calls.append((len(self.calls), self.clock.now()))


@contextlib.asynccontextmanager
async def running(ticker: Ticker) -> AsyncIterator[None]:
    task = asyncio.create_task(ticker.run(), name="ticker-under-test")
    await settle()
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def step_periods(clock: ManualClock, periods: int) -> None:
    """Move time one period at a time (the same float steps as the ticker's deadlines)."""
    for _ in range(periods):
        clock.advance(PERIOD)
        await settle()


def passed(clock: ManualClock) -> int:
    """Deadlines reached since the start at 0 (the tick at 0 included)."""
    return math.floor(clock.now() / PERIOD + 1e-9) + 1


async def test_idle_ticks_run_back_to_back_at_the_end_of_each_batch() -> None:
    clock = ManualClock()
    rec = Recorder(clock)
    ticker = Ticker(rec, PERIOD, clock, may_batch=Observed())
    async with running(ticker):
        assert ticker.count == 1  # the first tick runs at the start
        await step_periods(clock, IDLE_BATCH_TICKS - 1)
        assert ticker.count == 1  # deferred: nobody is looking
        assert ticker.batching
        await step_periods(clock, 1)  # the batch's last deadline
        assert ticker.count == 1 + IDLE_BATCH_TICKS
        await step_periods(clock, 2 * IDLE_BATCH_TICKS)
    assert ticker.count == 1 + 3 * IDLE_BATCH_TICKS
    # every tick ran once, in order, never before its deadline, at most a batch after it
    for index, when in rec.calls:
        assert index * PERIOD - 1e-9 <= when < (index + IDLE_BATCH_TICKS) * PERIOD
    assert [when for _, when in rec.calls[1 : 1 + IDLE_BATCH_TICKS]] == [
        pytest.approx(IDLE_BATCH_TICKS * PERIOD)
    ] * IDLE_BATCH_TICKS
    stats = ticker.stats()
    # deferred ticks are neither sampled nor late; the wake-ups were punctual
    assert stats.batched == 3 * (IDLE_BATCH_TICKS - 1)
    assert stats.overruns == 0
    assert stats.lateness_ms.max == pytest.approx(0.0, abs=1e-6)


async def test_catch_up_runs_exactly_the_ticks_due_none_lost_or_duplicated() -> None:
    clock = ManualClock()
    rec = Recorder(clock)
    ticker = Ticker(rec, PERIOD, clock, may_batch=Observed())
    async with running(ticker):
        for periods in (7, 1, 31, 12, 50, 3):  # observations at odd moments
            await step_periods(clock, periods)
            ticker.catch_up()
            assert ticker.count == passed(clock)
            await settle()  # the loop re-plans its batch
        await step_periods(clock, 250)
        ticker.catch_up()
        assert ticker.count == passed(clock) == 1 + 354
    assert [index for index, _ in rec.calls] == list(range(ticker.count))
    assert ticker.stats().overruns == 0


async def test_catch_up_does_nothing_without_batching() -> None:
    clock = ManualClock()
    ticker = Ticker(lambda: None, PERIOD, clock)
    async with running(ticker):
        await step_periods(clock, 10)
        assert ticker.catch_up() == 0
        assert not ticker.batching
        assert ticker.count == 11


async def test_a_waiter_wakes_at_its_ticks_deadline() -> None:
    clock = ManualClock()
    ticker = Ticker(lambda: None, PERIOD, clock, may_batch=Observed())
    woke: list[tuple[int, float]] = []

    async def waiter() -> None:
        await ticker.wait_ticks(3)
        woke.append((ticker.count, clock.now()))

    async with running(ticker):
        await step_periods(clock, 5)
        assert ticker.count == 1  # batching
        task = asyncio.create_task(waiter())
        await settle()
        assert ticker.count == 6  # wait_ticks counts from an up-to-date controller
        await step_periods(clock, 2)
        assert not woke
        await step_periods(clock, 1)
        assert woke == [(9, pytest.approx(8 * PERIOD))]
        await task


async def test_an_observer_makes_it_tick_every_period_again() -> None:
    clock = ManualClock()
    flag = Observed()
    ticker = Ticker(lambda: None, PERIOD, clock, may_batch=flag)
    async with running(ticker):
        await step_periods(clock, 10)
        assert ticker.count == 1
        flag.observed = True  # a client connects ...
        assert ticker.catch_up() == 10  # ... and its server catches the controller up
        await settle()
        for k in range(1, 6):
            await step_periods(clock, 1)
            assert ticker.count == 11 + k  # every period, in real time
        assert not ticker.batching
        flag.observed = False  # it left: batching again from the next tick
        await step_periods(clock, 2)
        assert ticker.count == 17
        assert ticker.batching


async def test_a_stall_in_a_batch_runs_the_deferred_ticks_and_resyncs_after() -> None:
    clock = ManualClock()
    ticker = Ticker(lambda: None, PERIOD, clock, may_batch=Observed())
    async with running(ticker):
        wake = IDLE_BATCH_TICKS * PERIOD
        clock.advance(wake + (RESYNC_PERIODS + 20) * PERIOD + 0.0005)  # a suspended VM
        await settle()
    # the 24 deferred ticks ran (never dropped); the late ones after the wake-up did not
    assert ticker.batched == IDLE_BATCH_TICKS - 1
    assert ticker.resyncs == 1
    assert ticker.skipped == RESYNC_PERIODS + 20
    assert ticker.count == 1 + (IDLE_BATCH_TICKS - 1) + 1


async def test_a_tick_failing_in_a_catch_up_stops_the_loop_not_the_caller() -> None:
    clock = ManualClock()
    calls = [0]

    def step() -> None:
        calls[0] += 1
        if calls[0] == 5:
            raise RuntimeError("tick 5 broke")

    ticker = Ticker(step, PERIOD, clock, may_batch=Observed())
    task = asyncio.create_task(ticker.run())
    await settle()
    await step_periods(clock, 10)
    assert ticker.catch_up() == 0  # the caller (a request, an accept) is not hurt
    await settle()
    assert task.done()
    with pytest.raises(RuntimeError, match="tick 5 broke"):
        task.result()
    assert ticker.count == 4


async def test_a_batched_controller_equals_one_ticked_in_real_time() -> None:
    """Two controllers, one batched: at every observation they are the same."""
    events = parse_scenario(
        {
            "events": [
                {"at": 0.25, "action": "hold", "on": True},
                {"at": 0.61, "action": "hold", "on": False},
                {"at": 0.9, "action": "estop", "pressed": True},
            ]
        }
    )
    pair = []
    for batching in (True, False):
        controller = VirtualController()
        controller.load_scenario(events)
        clock = ManualClock()
        ticker = Ticker(controller.tick, PERIOD, clock, may_batch=Observed() if batching else None)
        pair.append((controller, clock, ticker))
    async with running(pair[0][2]), running(pair[1][2]):
        for periods in (13, 40, 37, 90, 101, 7):
            for _, clock, _ in pair:
                await step_periods(clock, periods)
            batched, plain = pair
            batched[2].catch_up()
            assert batched[2].count == plain[2].count
            assert batched[0].snapshot() == plain[0].snapshot()
    assert pair[0][2].batched > 0
    assert pair[0][0].snapshot().estop  # the scenario ran


# --------------------------------------------------------------------------- real ports


def expected_counts(ticker: Ticker, before: float, after: float) -> range:
    """The tick counts an unbatched loop could show between ``before`` and ``after``."""
    deadline = ticker.next_deadline
    assert deadline is not None
    origin = deadline - (ticker.count + ticker.skipped) * ticker.period
    lo = math.floor((before - origin) / ticker.period) + 1 - ticker.skipped
    hi = math.floor((after - origin) / ticker.period) + 1 - ticker.skipped
    return range(lo, hi + 1)


MID_BATCH_S = IDLE_BATCH_TICKS * PERIOD / 2
"""Half a batch: an observation then lands where the controller lags by ~12 ticks unless
it is caught up. Not a synchronisation: the checks use the times measured around it."""


async def into_a_batch(ticker: Ticker) -> None:
    """Idle for two batches, then half-way into the next one."""
    async with asyncio.timeout(10.0):
        await ticker.wait_ticks(2 * IDLE_BATCH_TICKS)
    await asyncio.sleep(MID_BATCH_S)
    assert ticker.batching


async def test_after_idle_http_and_tcp_clients_see_an_up_to_date_controller() -> None:
    config = SimulatorConfig(host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=0)
    async with SimulatorApp(VirtualController(), config) as app:
        ticker = app.ticker
        assert app.idle_batching
        url = f"http://127.0.0.1:{app.ports.http}"
        async with httpx.AsyncClient(base_url=url) as http:
            for _ in range(3):
                await into_a_batch(ticker)
                before = time.monotonic()  # the precise clock's time line
                reply = await http.get("/api/state")
                after = time.monotonic()
                assert reply.status_code == 200
                assert reply.json()["tick"]["count"] in expected_counts(ticker, before, after)
        await into_a_batch(ticker)
        before = time.monotonic()
        peer = await Peer.connect(app.ports.state, Port.STATE)
        try:
            await peer.message()  # served after the accept caught the controller up
            after = time.monotonic()
            assert not ticker.batching  # a client: every period in real time
            assert app.controller.tick_count in expected_counts(ticker, before, after)
        finally:
            await peer.close()
        assert ticker.batched > 0


async def test_idle_batching_can_be_turned_off() -> None:
    async with SimulatorApp(VirtualController(), LOCAL, idle_batching=False) as app:
        await app.ticker.wait_ticks(2 * IDLE_BATCH_TICKS)
        assert not app.ticker.batching
        assert app.ticker.batched == 0


async def driver_session(batching: bool) -> tuple[list[WireMessage], object, int]:
    """Idle for 2 s of virtual time, then a ROS-driver-like session, time moved by hand."""
    clock = ManualClock()
    controller = VirtualController()
    app = SimulatorApp(controller, LOCAL, clock=clock, idle_batching=batching)
    replies: list[WireMessage] = []

    async def request(peer: Peer, message: WireMessage) -> None:
        await peer.send(message)
        await settle()
        task = asyncio.create_task(peer.message())
        for _ in range(5000):  # a pending request completes in a later tick
            await settle()
            if task.done():
                break
            clock.advance(PERIOD)
        replies.append(await task)

    async with app:
        await step_periods(clock, 500)
        assert app.ticker.batching is batching
        state = await Peer.connect(app.ports.state, Port.STATE)
        motion = await Peer.connect(app.ports.motion, Port.MOTION)
        await settle()
        await request(motion, MotoMotionCtrl(0, 0, MotionCommand.CHECK_MOTION_READY))
        await request(motion, MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
        start = JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6)
        end = JointTrajPtFull.for_joints(0, 1, 0.5, [0.2] + [0.0] * 5, [0.0] * 6)
        await request(motion, start)
        await request(motion, end)
        await step_periods(clock, 200)
        await request(motion, MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT))
        await request(motion, MotoMotionCtrl(0, 0, MotionCommand.STOP_TRAJ_MODE))
        await motion.close()
        await state.close()
        await settle()
        return replies, controller.snapshot(), app.ticker.count


async def test_a_driver_session_right_after_idle_is_the_same_as_without_batching() -> None:
    batched = await driver_session(True)
    plain = await driver_session(False)
    assert batched == plain
    assert len(batched[0]) == 6
