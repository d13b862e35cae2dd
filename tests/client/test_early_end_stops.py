"""Issue 29, item 1: whatever ends a streamed move early stops the robot.

Every way a Python move can end before it is done (``task.cancel()``,
``asyncio.wait_for``, ``asyncio.timeout``, an exception of the progress callback,
leaving the client's ``async with``) is tried at many points of a move (Hypothesis,
bounded), on the in-memory twin in virtual time. Each time the robot is judged by the
controller itself, tick by tick: the commanded pulses stop changing within a few
interpolation periods of the cancel, nothing stays queued, no further increment is
executed over the next second, the robot reports itself at rest, and the exception that
goes on says where it stopped (joint values with their unit). A cancelled point's reply
is consumed, not logged as "unexpected reply ... dropped".
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

import pytest
from hypothesis import given
from hypothesis import strategies as st
from slow_move import start_slow_move

from bounded_examples import bounded_examples
from pymotoros.client import FollowingSample
from pymotoros.client.errors import ConnectionLostError, MoveInProgressError
from pymotoros.client.stopping import EARLY_STOP_BOUND_S
from pymotoros.controller.cell import load_cell
from pymotoros.models.cell import load_cell_models
from pymotoros.protocol.constants import TCP_PORT_MOTION, TCP_PORT_STATE, MotionCommand
from pymotoros.testing import Twin, sync_twin, twin

GOAL: Final = (3.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""The issue's move: 3 rad on the S axis from home (about 1.6 s at full speed)."""
MAX_TICKS_AFTER_CANCEL: Final = 10
"""The commanded pulses may change for this many 4 ms ticks after the cancel: the
point in flight is answered, STOP_MOTION crosses to the controller and MotoROS waits up
to 20 ms for its interpolators (§3.6): 5 ticks, doubled for margin."""
MAX_COMMANDED_TRAVEL_RAD: Final = 0.02
"""The S axis's largest increment at full speed is about 0.009 rad per 4 ms tick."""
MAX_FEEDBACK_TRAVEL_RAD: Final = 0.1
"""The feedback lags the command by the servo's delay: it may move on by that much."""
FIXTURE_CELL: Final = (
    Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_table_fixture.toml"
)
"""A cell with obstacles: every move of its client is guarded."""
QUIET_AFTER_S: Final = 1.0
"""How long the controller is watched after the move ended: no increment may come."""

WAYS: Final = ("cancel", "timeout", "callback", "close")
"""``asyncio.wait_for`` runs on real time: it is tried over TCP (test_early_end_tcp.py)."""


class CallbackFailedError(Exception):
    """The caller's progress callback raised this."""


@dataclass
class TickLog:
    """The commanded pulses of every tick, with the twin's time (a tick hook)."""

    the_twin: Twin
    ticks: list[tuple[float, tuple[int, ...]]] = field(default_factory=list)

    def __call__(self) -> None:
        self.ticks.append((self.the_twin.clock.now(), self.the_twin.commanded_pulses(0)))

    def last_change_after(self, t: float) -> float:
        """Time of the last tick at or after ``t`` whose pulses differ from the tick before."""
        last = t
        for (_, before), (when, now) in zip(self.ticks, self.ticks[1:], strict=False):
            if when >= t and now != before:
                last = when
        return last

    def pulses_at(self, t: float) -> tuple[int, ...]:
        at = self.ticks[0][1]
        for when, pulses in self.ticks:
            if when > t:
                break
            at = pulses
        return at


@dataclass
class Outcome:
    error: BaseException
    cancelled_at: float
    log: TickLog
    travelled_rad: float
    """Commanded S-axis travel from the cancel to rest (rad)."""
    feedback_travel_rad: float
    """The same in the feedback (which lags the command by the servo's delay)."""
    rest_after_s: float
    """From the cancel until the commanded pulses stopped changing."""


MEASURED: list[Outcome] = []
"""Every run's numbers, for the worst-case summary test at the end of the file."""


async def _end_early(way: str, at_s: float) -> Outcome:
    async with Twin(robot="hc10") as the_twin:
        client = the_twin.client(timeout_s=2.0)
        await client.connect()
        await client.wait_for_state()
        await client.enable()
        log = TickLog(the_twin)
        the_twin.on_tick(log)
        started = asyncio.Event()
        cancelled_at: list[float] = []
        raise_after = [math.inf]

        feedback_at: list[float] = []

        def progress(sample: FollowingSample) -> None:
            started.set()
            if cancelled_at and not feedback_at and the_twin.clock.now() >= cancelled_at[0]:
                feedback_at.append((client.state.positions(0) or (0.0,))[0])
            if the_twin.clock.now() >= raise_after[0]:
                cancelled_at.append(the_twin.clock.now())
                raise CallbackFailedError("the caller's callback failed")

        move = client.move_joints(GOAL, on_progress=progress)
        error: BaseException | None = None
        t0 = the_twin.clock.now()
        try:
            if way == "timeout":
                # asyncio.timeout runs on the loop's (real) time; the twin's time is
                # virtual: the deadline is moved to "now" at the virtual moment instead.
                cancelled_at.append(t0 + at_s)
                async with asyncio.timeout(None) as deadline:
                    expire = asyncio.create_task(_expire(the_twin, deadline, t0 + at_s))
                    try:
                        await move
                    finally:
                        expire.cancel()
            elif way == "callback":
                raise_after[0] = t0 + at_s
                await move
            else:
                task = asyncio.create_task(move)
                await the_twin.sleep(at_s)
                assert not task.done(), "the move ended before the cancel"
                cancelled_at.append(the_twin.clock.now())
                if way == "cancel":
                    task.cancel()
                else:  # leaving ``async with``: what __aexit__ calls
                    await client.close()
                await task
        except BaseException as exc:
            error = exc
        assert error is not None, f"{way}: the move was not ended early"
        ended = the_twin.clock.now()
        fed_back = (client.state.positions(0) or (0.0,))[0]
        await the_twin.sleep(QUIET_AFTER_S)
        assert not the_twin.controller.has_queued_motion()
        assert client.state.status is None or client.state.status.in_motion is False
        at = cancelled_at[0]
        rest_at = log.last_change_after(at)
        assert rest_at <= ended, "an increment was executed after the move had ended"
        ratio = the_twin.robot.groups[0].axes[0].pulses_per_unit
        travelled = abs(log.pulses_at(math.inf)[0] - log.pulses_at(at)[0]) / ratio
        await client.close()
        at_cancel = feedback_at[0] if feedback_at else fed_back
        return Outcome(error, at, log, travelled, abs(fed_back - at_cancel), rest_at - at)


async def _expire(the_twin: Twin, deadline: asyncio.Timeout, at: float) -> None:
    await the_twin.clock.sleep_until(at)
    deadline.reschedule(asyncio.get_running_loop().time())


def _expected_type(way: str) -> type[BaseException]:
    return {
        "cancel": asyncio.CancelledError,
        "timeout": TimeoutError,
        "callback": CallbackFailedError,
        "close": asyncio.CancelledError,
    }[way]


def _all_notes(error: BaseException) -> str:
    """The notes of ``error`` and of its cause/context (``wait_for`` raises TimeoutError
    from the CancelledError that carries the note)."""
    notes: list[str] = []
    seen: BaseException | None = error
    while seen is not None:
        notes.extend(getattr(seen, "__notes__", ()))
        seen = seen.__cause__ or seen.__context__
    return "\n".join(notes)


@pytest.mark.parametrize("way", WAYS)
@bounded_examples(12)
@given(at_s=st.floats(min_value=0.02, max_value=1.4))
def test_a_move_ended_early_stops_the_robot(way: str, at_s: float) -> None:
    outcome = asyncio.run(_end_early(way, at_s))
    MEASURED.append(outcome)
    assert isinstance(outcome.error, _expected_type(way)), repr(outcome.error)
    assert outcome.rest_after_s <= MAX_TICKS_AFTER_CANCEL * 0.004 + 1e-9, (
        f"{way} at {at_s:.3f} s: the commanded pulses changed {outcome.rest_after_s:.3f} s "
        "after the cancel"
    )
    # At most one increment after the cancel (the tick at the same instant), and the
    # feedback catches up with the command by at most what the servo lags (the issue
    # saw 0.54 rad before this).
    assert outcome.travelled_rad < MAX_COMMANDED_TRAVEL_RAD
    assert outcome.feedback_travel_rad < MAX_FEEDBACK_TRAVEL_RAD
    notes = _all_notes(outcome.error)
    if outcome.log.ticks[0][1] == outcome.log.pulses_at(math.inf):
        return  # ended while it waited for rest or planned: nothing was sent, nothing moved
    assert "the robot was stopped (STOP_MOTION) and stands at [" in notes
    assert "] rad" in notes


@pytest.fixture(scope="module", autouse=True)
def _report_the_worst() -> Iterator[None]:
    """After the run: the worst travel after a cancel and the time to rest (the figures
    issue 29 asks for; ``pytest -s`` shows them, docs/client.md quotes them)."""
    yield
    if MEASURED:
        worst = max(o.travelled_rad for o in MEASURED)
        worst_fb = max(o.feedback_travel_rad for o in MEASURED)
        slowest = max(o.rest_after_s for o in MEASURED)
        print(
            f"\n{len(MEASURED)} early ends: worst commanded travel after the cancel "
            f"{worst:.4f} rad ({math.degrees(worst):.2f} deg), in the feedback "
            f"{worst_fb:.4f} rad; commanded pulses still after {slowest * 1000:.0f} ms"
        )


async def test_a_cancelled_point_reply_is_consumed_not_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Cancelled while a point is in flight: its reply comes after the cancel and is
    recognised as the owed reply (issue 29: "unexpected reply ... dropped")."""
    caplog.set_level(logging.DEBUG, logger="pymotoros.client.connection")
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        streamer = client.streamer
        in_flight = asyncio.Event()
        original = streamer.port.request_motion

        async def watched(message: object, *, timeout_s: float | None = None) -> object:
            if getattr(message, "sequence", 0) == 40:
                in_flight.set()
            return await original(message, timeout_s=timeout_s)  # type: ignore[arg-type]

        streamer.port = _Port(streamer.port, watched)
        task = asyncio.create_task(client.move_joints(GOAL))
        await in_flight.wait()
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        await the_twin.sleep(0.5)
    text = caplog.text
    assert "unexpected reply" not in text
    assert "does not answer" not in text
    assert "late reply" in text  # the point's reply did come, after the cancel


@dataclass
class _Port:
    """The client's motion port with ``request_motion`` replaced (to see a point in flight)."""

    inner: object
    request: Callable[..., object]

    async def request_motion(self, message: object, *, timeout_s: float | None = None) -> object:
        return await self.request(message, timeout_s=timeout_s)  # type: ignore[misc]

    def __getattr__(self, name: str) -> object:
        return getattr(self.inner, name)


async def test_a_second_cancel_during_the_stop_does_not_cut_it_short() -> None:
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        task = asyncio.create_task(client.move_joints(GOAL))
        await the_twin.sleep(0.5)
        task.cancel()
        for _ in range(3):  # the stop is under way: cancel it again, and again
            await asyncio.sleep(0)
            task.cancel()
        with pytest.raises(asyncio.CancelledError) as info:
            await task
        assert "stands at [" in _all_notes(info.value)
        pulses = the_twin.commanded_pulses(0)
        await the_twin.sleep(QUIET_AFTER_S)
        assert the_twin.commanded_pulses(0) == pulses
        assert not the_twin.controller.has_queued_motion()


async def test_an_error_mid_move_stops_the_robot_and_says_where() -> None:
    """A move that fails on its own (here: the completion wait's own time budget) stops
    the robot too; the client's error carries the position in its message."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        start = await client.current_positions()
        plan = client.plan(start, GOAL, speed_scale=0.2)  # about 0.2 s stays queued ahead
        with pytest.raises(Exception) as info:
            await client.execute(plan, timeout_s=0.05)
        assert type(info.value).__name__ == "MotionTimeoutError"
        assert "the robot was stopped (STOP_MOTION) and stands at [" in str(info.value)
        pulses = the_twin.commanded_pulses(0)
        await the_twin.sleep(QUIET_AFTER_S)
        assert the_twin.commanded_pulses(0) == pulses


async def test_a_stop_that_is_not_answered_says_stop_it_on_the_pendant() -> None:
    """STOP_MOTION with no answer: the note says so, with the last known position and
    what to do (the same words as a lost state stream)."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        task = asyncio.create_task(client.move_joints(GOAL))
        await the_twin.sleep(0.5)
        streamer = client.streamer

        async def silent(message: object, *, timeout_s: float | None = None) -> object:
            await the_twin.sleep(timeout_s or 1.0)
            from pymotoros.client.errors import RequestTimeoutError

            raise RequestTimeoutError(f"no reply to MotoMotionCtrl within {timeout_s:g} s")

        streamer.port = _Port(streamer.port, silent)
        task.cancel()
        with pytest.raises(asyncio.CancelledError) as info:
            await task
        notes = _all_notes(info.value)
        assert "STOP_MOTION could not be sent" in notes
        assert "stop the robot on the pendant" in notes
        assert "last known position [" in notes
        assert "] rad" in notes


async def test_the_stop_is_bounded() -> None:
    """A cancel holds the caller up no longer than the documented bound."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        task = asyncio.create_task(client.move_joints(GOAL))
        await the_twin.sleep(0.5)
        t0 = the_twin.clock.now()
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
        assert the_twin.clock.now() - t0 <= EARLY_STOP_BOUND_S


async def test_leaving_async_with_while_a_move_runs_stops_the_robot() -> None:
    """The block ends (here with an error) while a move runs in another task: __aexit__
    stops the robot before it closes the connections (MotoROS itself would go on with
    its queue after the motion connection closed, §2.2)."""
    async with Twin(robot="hc10") as the_twin:
        moving: list[asyncio.Task[object]] = []

        async def script() -> None:
            async with the_twin.client(timeout_s=2.0) as client:
                await client.wait_for_state()
                await client.enable()
                moving.append(asyncio.create_task(client.move_joints(GOAL)))
                await the_twin.sleep(0.5)
                raise RuntimeError("the script failed")

        with pytest.raises(RuntimeError, match="the script failed"):
            await script()
        (task,) = moving
        assert task.done()
        with pytest.raises(asyncio.CancelledError) as info:
            task.result()
        assert "the client is closing" in _all_notes(info.value)
        assert "stands at [" in _all_notes(info.value)
        pulses = the_twin.commanded_pulses(0)
        await the_twin.sleep(QUIET_AFTER_S)
        assert the_twin.commanded_pulses(0) == pulses
        assert not the_twin.controller.has_queued_motion()


def test_leaving_a_sync_with_block_while_another_thread_moves_stops_the_robot() -> None:
    """``with SyncRobotClient(...)`` (here the sync twin) ends while a thread is blocked
    in a move: the close stops the robot first; the moving thread gets the cancellation
    with the note."""
    with sync_twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        client.enable()
        move = start_slow_move(client, GOAL)
    error = move.error()
    assert "stands at [" in _all_notes(error), repr(error)
    assert not the_twin.controller.has_queued_motion()


async def test_the_progress_callback_gets_no_samples_during_the_stop() -> None:
    """The listener is detached before the stop: a callback that would raise during it
    (or the following monitor's blame) cannot turn the move's own error into a
    cancellation."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        start = await client.current_positions()
        plan = client.plan(start, GOAL, speed_scale=0.2)
        streamer = client.streamer
        original = streamer.port.request_motion
        stopping: list[float] = []

        async def watched(message: object, *, timeout_s: float | None = None) -> object:
            if getattr(message, "command", None) == MotionCommand.STOP_MOTION:
                stopping.append(the_twin.clock.now())
            return await original(message, timeout_s=timeout_s)  # type: ignore[arg-type]

        def progress(_sample: FollowingSample) -> None:
            if stopping:
                raise CallbackFailedError("a sample came during the stop")

        streamer.port = _Port(streamer.port, watched)
        with pytest.raises(Exception) as info:
            await client.execute(plan, timeout_s=0.05, on_progress=progress)
        assert stopping, "no STOP_MOTION was sent"
        assert type(info.value).__name__ == "MotionTimeoutError", repr(info.value)
        assert "the robot was stopped (STOP_MOTION) and stands at [" in str(info.value)


async def test_a_motion_connection_lost_mid_move_says_the_queue_may_still_run() -> None:
    """The motion port closes while the state stream lives: MotoROS goes on with the
    points it queued (§2.2) and STOP_MOTION cannot be sent: the error says so, what to do
    and the last known position with its unit."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        task = asyncio.create_task(client.move_joints(GOAL))
        await the_twin.sleep(0.5)
        await the_twin._services[TCP_PORT_MOTION].close_clients()
        with pytest.raises(ConnectionLostError) as info:
            await task
        text = str(info.value)
        assert "points already queued may still run" in text, text
        assert "stop the robot on the pendant" in text
        assert "last known position [" in text
        assert "] rad" in text


async def test_a_cancel_while_the_state_stream_is_lost_does_not_cut_the_stop_short() -> None:
    """The state stream goes mid-move and the client sends STOP_MOTION; a second cancel
    (a Ctrl-C) meanwhile must not keep it from going: the robot stops all the same."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        task = asyncio.create_task(client.move_joints(GOAL))
        await the_twin.sleep(0.5)
        streamer = client.streamer
        original = streamer.port.request_motion
        stop_asked = asyncio.Event()

        async def slow_stop(message: object, *, timeout_s: float | None = None) -> object:
            if getattr(message, "command", None) == MotionCommand.STOP_MOTION:
                stop_asked.set()
                await the_twin.sleep(0.1)  # the stop is under way when the cancel lands
            return await original(message, timeout_s=timeout_s)  # type: ignore[arg-type]

        streamer.port = _Port(streamer.port, slow_stop)
        await the_twin._services[TCP_PORT_STATE].close_clients()
        await stop_asked.wait()
        task.cancel()
        with pytest.raises(asyncio.CancelledError) as info:
            await task
        assert "STOP_MOTION acknowledged" in _all_notes(info.value) + str(info.value)
        await the_twin.sleep(0.2)
        pulses = the_twin.commanded_pulses(0)
        await the_twin.sleep(QUIET_AFTER_S)
        assert the_twin.commanded_pulses(0) == pulses
        assert not the_twin.controller.has_queued_motion()


async def test_a_second_execute_with_a_guarded_cell_is_refused_at_once() -> None:
    """With a cell that has obstacles, a second ``execute()`` while a move streams is
    refused before the workspace guard and without waiting for the first move's rest."""
    cell = FIXTURE_CELL
    async with Twin(load_cell(cell)) as the_twin:
        client = the_twin.client(cell=load_cell_models(cell), tool=0, timeout_s=2.0)
        await client.connect()
        await client.wait_for_state()
        await client.enable()
        start = await client.current_positions()
        goal = (start[0] + 0.5, *start[1:])
        moving = asyncio.create_task(client.move_joints(goal, speed_scale=0.2))
        await the_twin.sleep(0.3)
        plan = client.plan(client.state.positions(0) or start, start)
        t0 = the_twin.clock.now()
        with pytest.raises(MoveInProgressError, match=r"execute\(\) refused") as info:
            await client.execute(plan)
        assert the_twin.clock.now() == t0, "the refusal waited for the first move"
        assert "where it stopped" not in str(info.value)
        assert not moving.done()
        await moving
        await client.close()


async def test_a_callback_error_does_not_swallow_the_callers_cancel() -> None:
    """The caller cancels the move in the same instant as its progress callback raises:
    after the stop the cancellation goes on (it is not swallowed by the callback's error)."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        await client.enable()
        moving: list[asyncio.Task[object]] = []

        def progress(_sample: FollowingSample) -> None:
            if the_twin.clock.now() - t0 >= 0.5:
                moving[0].cancel()  # the caller's cancel...
                raise CallbackFailedError("...and the callback's error at once")

        t0 = the_twin.clock.now()
        moving.append(asyncio.create_task(client.move_joints(GOAL, on_progress=progress)))
        with pytest.raises(asyncio.CancelledError):
            await moving[0]
        pulses = the_twin.commanded_pulses(0)
        await the_twin.sleep(QUIET_AFTER_S)
        assert the_twin.commanded_pulses(0) == pulses
