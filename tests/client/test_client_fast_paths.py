"""The client's cheaper per-message and per-point paths against the ones they replace.

Each test runs the same input both ways and wants the very same result, float bits
included: the following monitor (plan lookup, progress, the sample and the report)
against its former code kept here as ``_FormerMonitor``; the speed screen against
:func:`speed_deviations`; the state tracker against a plain model of what it must
publish; the connection's read loop with wire logging on (the former, Frame-based path)
and off (straight from the buffer).
"""

from __future__ import annotations

import asyncio
import bisect
import logging
import math
import random
import struct
from typing import Any, cast

import pytest

from pymotoros.client.connection import FrameConnection
from pymotoros.client.following import (
    ARRIVED_PROGRESS,
    FollowingMonitor,
    FollowingSample,
    PathProgress,
)
from pymotoros.client.planning import JointLimits, JointTrajectory, TrajectoryPoint, plan_joint_move
from pymotoros.client.preflight import _f32_at_most, speed_deviations, speed_screen, within_screen
from pymotoros.client.state import JointState, RobotState, StateTracker, Status
from pymotoros.models import controller_model, robot_model
from pymotoros.models.rules import f32
from pymotoros.protocol.constants import ByteOrder, CommType, Port, ReplyType
from pymotoros.protocol.framing import Frame, encode, encode_frame
from pymotoros.protocol.messages import (
    JointFeedback,
    MotoJointFeedbackEx,
    MotoMotionReply,
    RobotStatus,
    WireMessage,
)

YRC1000 = controller_model("yrc1000")
HC10 = robot_model("hc10").groups[0]
LIMITS = JointLimits.from_group(HC10)
GOAL = (1.0, 0.5, 0.3, 0.2, -1.0, 0.5)
START = (0.0,) * 6


def _bits(value: object) -> object:
    """A value compared by its float bits (NaN equals NaN, -0.0 differs from 0.0)."""
    if isinstance(value, float):
        return struct.pack("<d", value)
    if isinstance(value, tuple):
        return tuple(_bits(v) for v in value)
    return value


@pytest.fixture(scope="module")
def plan() -> JointTrajectory:
    return plan_joint_move(START, GOAL, LIMITS, velocity_scaling=0.3, sample_period=0.02)


# --------------------------------------------------------------------------- plan lookup


def test_planned_at_is_position_at_bit_for_bit(plan: JointTrajectory) -> None:
    monitor = FollowingMonitor(plan, (0,))
    rng = random.Random("planned-at")
    end = plan.duration
    times = [p.time for p in plan.points]
    probes = [-1.0, 0.0, 1e-12, end, end + 1.0, *times]
    probes += [math.nextafter(t, math.inf) for t in times]
    probes += [math.nextafter(t, -math.inf) for t in times]
    probes += [rng.uniform(-0.1, end + 0.1) for _ in range(3000)]
    for t in probes:
        assert _bits(monitor._planned_at(t)) == _bits(plan.position_at(t)), t


def test_planned_at_of_odd_plans_is_position_at() -> None:
    """Times that do not start at 0 or do not increase keep the former lookup."""
    pts = [
        TrajectoryPoint(t, (t, -t), (1.0, 0.5))
        for t in (0.5, 0.2, 0.9, 0.9, 1.4, 1.1, 2.0)  # neither from 0 nor increasing
    ]
    plan = JointTrajectory(tuple(pts), 2.0)
    monitor = FollowingMonitor(plan, (0,))
    former = _FormerMonitor(plan, (0,))
    for t in [0.1 * k for k in range(-2, 25)] + [0.2, 0.5, 0.9, 1.1, 1.4]:
        try:
            want: object = _bits(former._planned_at(t))
        except Exception as exc:  # the former code's own failure, if any, is kept too
            want = (type(exc), str(exc))
        try:
            got: object = _bits(monitor._planned_at(t))
        except Exception as exc:
            got = (type(exc), str(exc))
        assert got == want, t


def test_progress_is_the_plans_bit_for_bit(plan: JointTrajectory) -> None:
    progress = PathProgress(plan)
    rng = random.Random("progress")
    for _ in range(2000):
        positions = tuple(rng.uniform(-2, 2) for _ in range(6))
        assert _bits(progress(positions)) == _bits(plan.progress(positions))
    with pytest.raises(ValueError):  # a wrong length stays zip's strict error
        progress((0.0,) * 5)
    with pytest.raises(ValueError):
        plan.progress((0.0,) * 5)


# --------------------------------------------------------------------------- monitor


class _FormerMonitor(FollowingMonitor):
    """The following monitor's per-message code as it was before the fast path."""

    def update(self, state: RobotState) -> FollowingSample | None:
        if self._t0 is None:
            return None
        positions = state.positions(0)
        if positions is None:
            return None
        elapsed = self.clock.now() - self._t0
        planned = self._planned_at(elapsed)
        error = max((abs(a - b) for a, b in zip(positions, planned, strict=False)), default=0.0)
        progress = min(max(self._progress_former(positions), 0.0), 1.0)
        reached = self._time_at_progress(progress)
        lag = max(0.0, elapsed - reached) if progress < ARRIVED_PROGRESS else 0.0
        speed_pct = self._speed_pct(elapsed, reached, progress)
        sample = FollowingSample(elapsed, progress, lag, error, speed_pct)
        rep = self.report
        rep.samples += 1
        rep.max_error = max(rep.max_error, error)
        rep.max_lag_s = max(rep.max_lag_s, lag)
        rep.min_speed_pct = min(rep.min_speed_pct, speed_pct)
        if lag > self.warn_lag_s and not rep.slowed:
            rep.slowed = True
        self.last = sample
        return sample

    def _progress_former(self, positions: tuple[float, ...]) -> float:
        return self.trajectory.progress(positions)

    def _planned_at(self, t: float) -> tuple[float, ...]:
        pts = self.trajectory.points
        if t <= 0.0 or len(pts) == 1:
            return pts[0].positions
        if t >= pts[-1].time:
            return pts[-1].positions
        i = bisect.bisect_right(self._times, t) - 1
        if i < 0:
            return self.trajectory.position_at(t)
        segment = JointTrajectory((pts[i], pts[i + 1]), pts[i + 1].time)
        return segment.position_at(t)


class _Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def now(self) -> float:
        return self.t

    async def sleep(self, seconds: float) -> None:
        self.t += seconds


def _state(positions: tuple[float, ...]) -> RobotState:
    from types import MappingProxyType

    return RobotState(None, MappingProxyType({0: JointState(0, positions, None, 0.0)}), 1, 1)


def test_monitor_samples_and_report_equal_the_former(plan: JointTrajectory) -> None:
    """A robot that lags, stops (HOLD), overshoots, jitters and sends NaN: same samples."""
    clock = _Clock()
    new = FollowingMonitor(plan, (0,), clock=clock)
    old = _FormerMonitor(plan, (0,), clock=clock)
    new.start()
    old.start()
    rng = random.Random("monitor")
    t_plan = 0.0
    for step in range(int(plan.duration / 0.025) * 2 + 40):
        clock.t += 0.025
        if not 40 <= step < 80:  # a hold: the plan's time stands still
            t_plan += 0.025 * (0.3 if step % 200 < 50 else 1.0)
        positions = tuple(p + rng.gauss(0.0, 1e-4) for p in plan.position_at(t_plan))
        if step % 97 == 5:
            positions = (math.nan, *positions[1:])
        if step % 131 == 7:
            positions = tuple(g + 0.01 for g in GOAL)  # past the goal
        state = _state(positions)
        got, want = new.update(state), old.update(state)
        assert got is not None
        assert want is not None
        assert _bits(_sample_tuple(got)) == _bits(_sample_tuple(want)), step
    assert _bits(_report_tuple(new)) == _bits(_report_tuple(old))
    assert new.report.samples == old.report.samples > 100


def _sample_tuple(s: FollowingSample) -> tuple[float, ...]:
    return (s.elapsed_s, s.progress, s.lag_s, s.error, s.speed_pct)


def _report_tuple(m: FollowingMonitor) -> tuple[object, ...]:
    r = m.report
    # The former ``slowed`` meant "fell behind by more than the threshold"; issue 29 split
    # it by cause (slowed, late), and ``reason`` is set whenever it fell behind.
    behind = r.slowed if isinstance(m, _FormerMonitor) else bool(r.reason)
    return (r.samples, r.max_lag_s, r.max_error, behind, r.min_speed_pct)


# --------------------------------------------------------------------------- speed screen


def test_screen_limit_is_the_float32_at_or_below() -> None:
    rng = random.Random("f32-below")
    for limit in [0.0, 1.0, 3.14159, 1e-30, 2.0**-140, *(rng.uniform(0, 10) for _ in range(500))]:
        below = _f32_at_most(limit)
        assert f32(below) == below <= limit
        (bits,) = struct.unpack("<I", struct.pack("<f", below))
        (up,) = struct.unpack("<f", struct.pack("<I", bits + 1))
        assert up > limit
    for bad in (-1.0, math.nan, math.inf, 3e9):
        assert _f32_at_most(bad) == -1.0


def test_within_screen_means_speed_deviations_finds_and_logs_nothing(
    caplog: pytest.LogCaptureFixture,
) -> None:
    screen = speed_screen([HC10], YRC1000)
    limits = [_f32_at_most(v) for v in LIMITS.max_velocity]
    rng = random.Random("screen")
    edges: list[float] = []
    for lim in screen:
        f = float(lim)
        edges += [f, -f, math.nextafter(f, 0), math.nextafter(f, math.inf), f * 1.0000001]
    edges += [math.nan, math.inf, -math.inf, 0.0, -0.0, 1.4e-45]
    screened = 0
    for trial in range(4000):
        vel = [
            rng.choice(edges) if rng.random() < 0.2 else rng.uniform(-1.1, 1.1) * screen[i]
            for i in range(6)
        ]
        if trial % 50 == 0:
            vel[rng.randrange(6)] = 1  # an int: a plain number too
        point = TrajectoryPoint(0.1, START, tuple(vel))
        caplog.clear()
        with caplog.at_level(logging.WARNING):
            devs = speed_deviations(point, [HC10], YRC1000)
        if within_screen(point.velocities, screen):
            screened += 1
            assert devs == [], vel
            assert not caplog.records, vel
    assert 500 < screened < 4000
    assert limits  # the plan's own limits are within the screen at the points planned


def test_within_screen_refers_odd_values_to_the_full_check() -> None:
    screen = speed_screen([HC10], YRC1000)
    assert not within_screen((math.nan,) + (0.0,) * 5, screen)
    assert not within_screen((True,) + (0.0,) * 5, screen)
    assert not within_screen(cast(Any, ("0.1",) + (0.0,) * 5), screen)
    assert within_screen((0.0,) * 6, screen)


# --------------------------------------------------------------------------- state tracker


def _random_message(rng: random.Random) -> WireMessage:
    roll = rng.random()
    if roll < 0.4:
        return RobotStatus(*(rng.choice((0, 1, 1, 1, -1, 2)) for _ in range(7)))
    if roll < 0.8:
        pos = [rng.choice((0.0, rng.uniform(-3, 3))) for _ in range(rng.randrange(0, 11))]
        if rng.random() < 0.1 and pos:
            pos[-1] = math.nan
        vel = [rng.uniform(-1, 1) for _ in range(len(pos))] if rng.random() < 0.7 else None
        return JointFeedback.for_joints(rng.randrange(0, 3), pos, vel)
    groups = [
        JointFeedback.for_joints(g, [rng.uniform(-1, 1)] * rng.randrange(1, 9), [0.5])
        for g in range(rng.randrange(0, 3))
    ]
    return MotoJointFeedbackEx.for_groups(groups)


def test_tracker_publishes_what_the_messages_say() -> None:
    """A plain model of the tracker's states, statuses, trimming and groups seen."""
    rng = random.Random("tracker")
    now = iter(float(k) for k in range(100000))
    axes = {0: 6, 1: 2}
    tracker = StateTracker(axes, now=lambda: next(now))
    seen: list[RobotState] = []
    tracker.add_listener(seen.append)
    status: Status | None = None
    joints: dict[int, JointState] = {}
    statuses = 0
    cycle: dict[int, int] = {}
    groups_seen: dict[int, int] | None = None
    clock = 0.0
    for count in range(1, 3001):
        message = _random_message(rng)
        tracker.feed(message)
        received = clock
        clock += 1.0
        if isinstance(message, RobotStatus):
            status = Status.from_message(message)
            statuses += 1
            if statuses >= 2:
                groups_seen = dict(cycle)
            cycle = {}
        else:
            records = [message] if isinstance(message, JointFeedback) else message.groups
            for fb in records:
                n = axes.get(fb.group_no, 8)
                vel = fb.vel[:n] if fb.valid_fields & 4 else None
                joints[fb.group_no] = JointState(fb.group_no, fb.pos[:n], vel, received)
                used = max((i + 1 for i, v in enumerate(fb.pos) if v != 0.0), default=0)
                cycle[fb.group_no] = max(used, cycle.get(fb.group_no, 0))
        state = tracker.state
        assert seen[-1] is state
        assert repr(state.status) == repr(status)
        assert _bits(repr(dict(state.joints))) == _bits(repr(joints))
        assert (state.count, state.status_count) == (count, statuses)
        assert (None if tracker.groups_seen is None else dict(tracker.groups_seen)) == groups_seen


def test_listeners_added_or_removed_while_called() -> None:
    tracker = StateTracker()
    calls: list[str] = []
    remove_a = tracker.add_listener(lambda _s: (calls.append("a"), remove_a()))

    def b(_state: RobotState) -> None:
        calls.append("b")
        tracker.add_listener(lambda _s: calls.append("c"))

    tracker.add_listener(b)
    tracker.feed(RobotStatus(1, 0, 0, 0, 0, 2, 1))  # a removes itself, b adds c: both ran
    assert calls == ["a", "b"]
    calls.clear()
    tracker.feed(RobotStatus(1, 0, 0, 0, 0, 2, 1))
    assert calls == ["b", "c"]


async def test_waiters_wake_on_the_next_message_after_silent_publishes() -> None:
    tracker = StateTracker()
    for _ in range(3):  # nobody waits: nothing to wake
        tracker.feed(RobotStatus(1, 0, 0, 0, 0, 2, 1))
    waiter = asyncio.ensure_future(tracker.next_state(timeout_s=5.0))
    other = asyncio.ensure_future(tracker.wait_for(lambda s: s.count >= 5, 5.0))
    await asyncio.sleep(0)
    tracker.feed(JointFeedback.for_joints(0, [0.5]))
    state = await waiter
    assert state.count == 4
    assert state.positions(0) == (0.5,) + (0.0,) * 7  # 8 slots: no axis count was given
    assert not other.done()
    tracker.feed(RobotStatus(1, 0, 0, 0, 0, 2, 1))
    assert (await other).count == 5
    assert tracker._waiting == 0


# --------------------------------------------------------------------------- read loop


class _Writer:
    def write(self, data: bytes) -> None:
        pass

    async def drain(self) -> None:
        pass

    def close(self) -> None:
        pass

    async def wait_closed(self) -> None:
        pass

    def get_extra_info(self, _name: str) -> None:
        return None


async def _received(stream: bytes, chunk: int) -> tuple[list[object], str]:
    reader = asyncio.StreamReader()
    topics: list[object] = []
    conn = FrameConnection(
        reader,
        cast(asyncio.StreamWriter, _Writer()),
        kind=Port.STATE,
        host="127.0.0.1",
        port=1,
        order=ByteOrder.LITTLE,
        on_topic=topics.append,
    )
    for at in range(0, len(stream), chunk):
        reader.feed_data(stream[at : at + chunk])
        await asyncio.sleep(0)
    reader.feed_eof()
    await conn.closed.wait()
    await conn.close()
    assert conn.error is not None
    return topics, str(conn.error)


@pytest.mark.parametrize("chunk", [1, 37, 4096])
async def test_read_loop_fast_and_logged_paths_agree(
    chunk: int, caplog: pytest.LogCaptureFixture
) -> None:
    rng = random.Random(f"read-loop-{chunk}")
    frames = []
    for _ in range(200):
        message: WireMessage = _random_message(rng)
        frames.append(encode(message, ByteOrder.LITTLE))
        if rng.random() < 0.1:  # a reply on the state port: not a topic, dropped with a warning
            frames.append(encode(MotoMotionReply(0, 1, 2, 0, 0), ByteOrder.LITTLE))
        if rng.random() < 0.05:  # an unknown topic
            frames.append(encode_frame(Frame(777, CommType.TOPIC, ReplyType.INVALID, b"x"), "<"))
    frames.append(encode_frame(Frame(15, CommType.TOPIC, ReplyType.INVALID, bytes(5)), "<"))
    stream = b"".join(frames)  # ends with a JOINT_FEEDBACK of the wrong size: the loop stops
    fast, fast_error = await _received(stream, chunk)
    with caplog.at_level(logging.DEBUG, logger="pymotoros.client.wire"):
        logged, logged_error = await _received(stream, chunk)
    assert any("<- type 15" in r.getMessage() for r in caplog.records)
    assert [repr(m) for m in fast] == [repr(m) for m in logged]
    assert len(fast) > 200
    assert fast_error == logged_error
    assert "undecodable data" in fast_error
