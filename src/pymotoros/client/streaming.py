"""Streaming a trajectory to MotoROS and watching the robot follow it.

:class:`TrajectoryStreamer` does it all, against a narrow interface (a
:class:`~pymotoros.client.motion_port.MotionPort`, a
:class:`~pymotoros.client.motion_port.StateSource`, the models and an injected
:class:`~pymotoros.client.timing.ClientClock`):

* :meth:`~TrajectoryStreamer.send_points`: JOINT_TRAJ_PT_FULL (one group) or
  JOINT_TRAJ_PT_FULL_EX (several), sequence 0..N-1, each offered when MotoROS can take
  it (:class:`BusyPolicy`). BUSY (the previous point is still
  being turned into increments, §3.4) is retried with a short, growing back-off under
  a per-point time budget; any other refusal raises the typed error with the point
  index and the numbers behind it.
* :meth:`~TrajectoryStreamer.wait_until_at_rest`: ``in_motion`` false and the feedback
  still; its positions are the "start from current" point 0.
* :class:`FollowingMonitor`: compares feedback with the plan while the robot moves and
  reports how far behind it runs (how a safety speed limit shows up).
* :meth:`~TrajectoryStreamer.wait_for_completion`: queue empty, ``in_motion`` false,
  feedback settled within a tolerance of the goal; judged against progress, not only
  the clock.
* :meth:`~TrajectoryStreamer.stop_early`: whatever ends :meth:`~TrajectoryStreamer.execute`
  before the goal (a cancel, a timeout, the caller's callback, an error) first stops
  the robot (STOP_MOTION, then at rest, within :data:`EARLY_STOP_BOUND_S`) and then
  lets the cancellation or error go on, saying where the robot stopped.

Every wait ends: on success, on a typed error, on a timeout, or at once with
:class:`ConnectionLostError` when a connection drops. The MotoROS rules used to
explain a refusal (:func:`start_deviations`, :func:`speed_deviations`) are plain
functions.
"""

from __future__ import annotations

import asyncio
import bisect
import collections
import enum
import itertools
import logging
import math
import operator
from collections.abc import Callable, Coroutine, Sequence
from dataclasses import KW_ONLY, dataclass, field
from typing import Final, TypeVar

from pymotoros.client.errors import (
    AxisDeviation,
    ClientError,
    ConnectionLostError,
    EarlyStop,
    MotionConnectionLostError,
    MotionIncompleteError,
    MotionTimeoutError,
    ReplyError,
    RequestTimeoutError,
    StateStreamLostError,
    reply_error,
)
from pymotoros.client.motion_port import MotionPort, StateSource
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.preflight import (
    speed_deviations,
    speed_screen,
    start_deviations,
    within_screen,
)
from pymotoros.client.state import RobotState
from pymotoros.client.timing import REAL_TIME, ClientClock
from pymotoros.client.watchdog import DEFAULT_STATE_STALL_S, StallWatchdog
from pymotoros.log_tags import AS_NOTE, AS_STOP_REPORT
from pymotoros.models import ControllerModel, GroupModel, RobotModel
from pymotoros.models.rules import START_TOLERANCE_PULSES
from pymotoros.protocol.constants import InvalidSubcode, MotionCommand, MsgType, ResultCode
from pymotoros.protocol.messages import (
    JointTrajPtExData,
    JointTrajPtFull,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
)

logger = logging.getLogger(__name__)

DEFAULT_BUSY_TIMEOUT_S: Final = 10.0
"""How long one point may keep getting BUSY. A full queue is 0.8 s of motion (§5.1);
a safety speed limit can stretch that, so the budget is generous."""

BUSY_BACKOFF_FIRST_S: Final = 0.0005
BUSY_BACKOFF_MAX_S: Final = 0.002
"""Retry BUSY after 0.5 ms, doubling up to 2 ms. MotoROS frees its one pending-point slot
at an interpolation tick (4 ms, §5.3), so with points one tick apart a longer back-off
(the ROS driver waits ~5 ms) cannot keep the 200-entry queue fed and the robot lags.
Any gap under one tick lands a retry in the tick interval right after the slot frees:
the point is taken at the earliest tick it can be."""

BUSY_KEEP_AHEAD_S: Final = 0.2
"""Motion the client keeps queued ahead of the robot before it waits longer than the
back-off above: with more than this buffered, a BUSY retry waits up to one segment's
duration instead (the pending slot frees once the segment before it is queued, §5.3),
so a full queue costs about one BUSY per point instead of one every millisecond.
0.2 s is a quarter of MotoROS's 200-entry queue at 4 ms (0.8 s, §5.1): far more than
a LAN round trip or a scheduling hiccup of the client."""

BUSY_RELAXED_MAX_S: Final = 0.1
"""Longest single wait before an offer or between BUSY retries, so a lost connection is
still noticed fast: a tenth of the state-stall bound (``DEFAULT_STATE_STALL_S``, 1 s)."""


class BusyPolicy(enum.StrEnum):
    """When the next point is first offered (:attr:`TrajectoryStreamer.busy_policy`).

    Both retry BUSY the same way (:data:`BUSY_BACKOFF_FIRST_S`, :data:`BUSY_KEEP_AHEAD_S`)
    and give the robot the same motion; they differ in the first offer of each point.
    """

    PACED = "paced"
    """The default. A point that follows an accepted point (sequence > 0) is not offered
    before one interpolation period after that point was *sent*, nor, while more than
    :data:`BUSY_KEEP_AHEAD_S` is queued, before the relaxed wait
    (:meth:`_Pacing.first_wait`). MotoROS clears its pending-point
    flag only in its AddToIncQueue task, once per tick (§5.3): an offer in the same tick
    interval as the previous acceptance is certain to get BUSY. About one offer per
    point instead of two (points far apart) to four or five (points one tick apart)."""
    IMMEDIATE = "immediate"
    """Offer every point the moment the previous one was accepted, as pymotoros did up
    to issue 22 (kept so that tests can show both give the robot the same increments)."""


DEFAULT_GOAL_TOLERANCE: Final = 1e-4
"""rad (m): how close every joint must come to the goal (a few pulses on most arms)."""

SETTLE_STEP: Final = 2e-5
"""rad (m): feedback that moves less than this between two state messages is at rest."""

SETTLE_SAMPLES: Final = 3
"""Consecutive quiet state messages needed to call the robot settled (~75 ms at 40 Hz)."""

DEFAULT_SETTLE_TIMEOUT_S: Final = 5.0
"""Extra time after the planned duration for the robot to settle."""

STALL_TIMEOUT_S: Final = 2.0
"""Past the planned duration, a robot that makes no progress for this long has stopped."""

STOP_TIMEOUT_S: Final = 1.0
"""How long STOP_MOTION may take after the state stream was lost."""

STOP_REST_TIMEOUT_S: Final = 2.0
"""After STOP_MOTION, how long the feedback may take to show the robot at rest
(``in_motion`` false, still for :data:`SETTLE_SAMPLES` state cycles). MotoROS stops at
once (no ramp, §3.6): what is left is the servo's own lag and three quiet state cycles
(~75 ms), so 2 s is ample and still short enough for a person waiting on Ctrl-C."""

EARLY_STOP_BOUND_S: Final = STOP_TIMEOUT_S + STOP_REST_TIMEOUT_S
"""The longest a move that ends early holds up its cancellation or error to stop the
robot: the STOP_MOTION reply plus the wait for rest (3 s; docs/client.md)."""

STOP_ON_THE_PENDANT: Final = "stop the robot on the pendant"
"""What to do when STOP_MOTION could not be sent or was not answered (one wording, here)."""

LAG_WARNING_S: Final = 0.25
"""A robot this far behind the plan is being slowed (a safety speed limit, HOLD…)."""


_SAME_POSITION: Final = 1e-12
"""Squared distance under which start and goal coincide (as ``JointTrajectory.progress``)."""

SPEED_WINDOW_S: Final = 0.2
"""Window of the following monitor's speed estimate: eight state cycles of 25 ms, long
enough to smooth the encoder steps, short enough to see an FSU switch within a cycle."""
ARRIVED_PROGRESS: Final = 0.999
"""Progress from which the following monitor counts the robot as arrived (no lag)."""

SLOWED_SPEED_PCT: Final = 90.0
"""Below this share of the planned speed in the robot's own velocity report (the state
stream's feedback velocities), the robot is being slowed (FSU, override, HOLD); at or
above it, a robot that still falls behind is waiting on a late controller or network.
Chosen: a robot on the plan reports about 100 % (the twin 99–101 %), an FSU limit or an
override far less, HOLD 0."""

STATE_PERIOD_S: Final = 0.025
"""MotoROS sends a state cycle every 25 ms (reference §2.3)."""

LATE_STATE_GAP_S: Final = 4 * STATE_PERIOD_S
"""A gap between state messages this long (four cycles) means late feedback."""

_STILL_PLAN: Final = 1e-12
"""Squared planned speed under which the plan stands still (no speed to compare with)."""


@dataclass(frozen=True, slots=True)
class ExecuteOptions:
    """How one whole move is streamed and judged, as :meth:`RobotClient.execute` was
    asked: one bundle handed down from the public method, not its keywords copied."""

    busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S
    goal_tolerance: float = DEFAULT_GOAL_TOLERANCE
    timeout_s: float | None = None
    check_speed: bool = True
    on_progress: Callable[[FollowingSample], None] | None = None


@dataclass(slots=True)
class StreamStats:
    """What streaming one trajectory took."""

    points: int = 0
    busy_replies: int = 0
    max_busy_wait_s: float = 0.0
    elapsed_s: float = 0.0

    @property
    def offers(self) -> int:
        """Points sent, retries included: each offer was accepted or answered BUSY."""
        return self.points + self.busy_replies


@dataclass(frozen=True, slots=True)
class FollowingSample:
    """One comparison of feedback with the plan."""

    elapsed_s: float
    """Since the robot was told to start."""
    progress: float
    """Fraction of the move done (0..1), from the feedback."""
    lag_s: float
    """How far behind the plan the robot is, in time (≥ 0)."""
    error: float
    """Largest joint difference between feedback and plan now (rad or m): the lag in rad."""
    speed_pct: float = 100.0
    """The robot's speed along the plan in % of the planned speed, over the last
    :data:`SPEED_WINDOW_S` (100: on plan; an FSU joint-speed limit of 30 % shows as ~30)."""


@dataclass(slots=True)
class FollowingReport:
    """Summary of how the robot followed the plan."""

    samples: int = 0
    max_lag_s: float = 0.0
    max_error: float = 0.0
    slowed: bool = False
    """The robot fell more than the warning threshold behind the plan because it was
    slowed: the speed it reports itself was below the plan's (FSU, override, HOLD)."""
    late: bool = False
    """It fell behind although it reported the planned speed: the controller or the
    network was late (a loaded simulator, a stalled loop, delayed state messages)."""
    reason: str = ""
    """Why it fell behind, with the numbers used (the warning that was logged)."""
    min_speed_pct: float = 100.0
    """The lowest :attr:`FollowingSample.speed_pct` seen while the plan was moving."""
    max_state_gap_s: float = 0.0
    """The longest silence between two state messages while the monitor listened."""

    @property
    def max_lag_rad(self) -> float:
        """The largest lag in rad (or m): :attr:`max_error`."""
        return self.max_error


@dataclass(frozen=True, slots=True)
class MoveResult:
    """How a move went."""

    trajectory: JointTrajectory
    final_positions: tuple[float, ...]
    stream: StreamStats
    following: FollowingReport
    elapsed_s: float
    """From the first point sent to settled at the goal."""
    groups: tuple[int, ...] = field(default=(0,))


def _split(values: Sequence[float], sizes: Sequence[int]) -> list[tuple[float, ...]]:
    out, i = [], 0
    for n in sizes:
        out.append(tuple(values[i : i + n]))
        i += n
    return out


def _joined_positions(state: RobotState, groups: Sequence[int]) -> tuple[float, ...] | None:
    values: list[float] = []
    for g in groups:
        pos = state.positions(g)
        if pos is None:
            return None
        values.extend(pos)
    return tuple(values)


def build_message(
    point: TrajectoryPoint, sequence: int, groups: Sequence[int], sizes: Sequence[int]
) -> JointTrajPtFull | MotoJointTrajPtFullEx:
    """Type 14 for one group, 2016 for several (one sequence for all, §3.5)."""
    pos = _split(point.positions, sizes)
    vel = _split(point.velocities, sizes)
    acc = _split(point.accelerations, sizes) if point.accelerations else [None] * len(sizes)
    if len(groups) == 1:
        return JointTrajPtFull.for_joints(groups[0], sequence, point.time, pos[0], vel[0], acc[0])
    return MotoJointTrajPtFullEx.for_groups(
        sequence,
        [
            JointTrajPtExData.for_joints(g, point.time, p, v, a)
            for g, p, v, a in zip(groups, pos, vel, acc, strict=True)
        ],
    )


def _deviation_text(
    devs: Sequence[AxisDeviation], kind: str, models: Sequence[GroupModel] = ()
) -> str:
    """The numbers of a refusal with their units (rad, rad/s; m, m/s for a linear axis
    of ``models``, the refused groups' models in order)."""
    linear = {i for i, a in enumerate(a for m in models for a in m.axes) if a.linear}
    if kind == "start":
        return "; ".join(
            f"{d.name} {d.pulses} pulses ({d.difference:+.5f} "
            f"{'m' if d.axis in linear else 'rad'}) from the robot, "
            f"tolerance {START_TOLERANCE_PULSES} pulses"
            for d in devs
        )
    return "; ".join(
        f"{d.name} {d.value:+.4f} {unit} > limit {d.reference:.4f} {unit}"
        for d in devs
        for unit in ("m/s" if d.axis in linear else "rad/s",)
    )


deviation_text: Final = _deviation_text
"""The per-joint numbers of a 3011 ("start") or 3013 ("speed") refusal, public so that a
check made before sending (``pymotoros run``) words them as the refusal does."""


@dataclass(slots=True)
class _Pacing:
    """How much accepted motion is still ahead of the robot, estimated from the clock,
    and when MotoROS can next take a point.

    The robot cannot be ahead of the trajectory's own time since point 0 was accepted
    (it can only be behind, under HOLD or a safety speed limit), so ``last point's time
    − time since point 0`` never overstates what MotoROS still has queued.
    """

    start: float
    """Clock time at which point 0 was accepted."""
    last_time: float
    """Trajectory time of the last accepted point."""
    last_segment: float = 0.0
    """Duration of the last accepted segment."""
    period: float = 0.0
    """The controller's interpolation period (s): how often its pending slot can free."""
    sent_at: float = 0.0
    """Clock time at which the latest offer was sent (once accepted: the last point's)."""
    slot_held: bool = False
    """The last accepted point holds the pending slot (sequence > 0; point 0 does not:
    it starts the trajectory at once, §3.4)."""

    def accepted(self, time_s: float) -> None:
        self.last_segment = time_s - self.last_time
        self.last_time = time_s
        self.slot_held = True

    def relaxed_wait(self, now: float) -> float:
        """How long a BUSY retry may wait without letting the queue run low (0: don't)."""
        spare = self.last_time - (now - self.start) - BUSY_KEEP_AHEAD_S
        return max(0.0, min(spare, self.last_segment, BUSY_RELAXED_MAX_S))

    def first_wait(self, now: float) -> float:
        """How long to wait before the first offer of the next point (:attr:`BusyPolicy.PACED`).

        * One period after the last point was sent: it reached MotoROS one one-way
          delay after that, and the pending slot frees at the first tick after its
          arrival (when the queue has room), at most one period later. So the next
          point arrives in the tick interval right after that tick, the one the
          immediate policy's 0.5–2 ms retries land in: the same tick takes it, and
          points one tick apart still go in one per tick (each sent one period after
          the last, whatever the round trip). A round trip longer than a period
          leaves no wait.
        * With more than :data:`BUSY_KEEP_AHEAD_S` queued, the relaxed wait instead,
          when longer: the time at which the immediate policy's first retry would go
          (its offer at once is a certain BUSY), so the point is accepted at that same
          time.
        """
        if not self.slot_held:
            return 0.0
        return max(self.relaxed_wait(now), self.sent_at + self.period - now)


@dataclass(eq=False, repr=False)
class TrajectoryStreamer:
    """Streams trajectories to one controller and watches the robot follow them.

    It depends only on a :class:`~pymotoros.client.motion_port.MotionPort` (request,
    queue count, readiness), a :class:`~pymotoros.client.motion_port.StateSource`
    (the state stream), the robot and controller models, and a
    :class:`~pymotoros.client.timing.ClientClock` for every "now" and "sleep": a test
    can drive it with an in-memory pair in virtual time. ``RobotClient`` builds one
    around itself.
    """

    port: MotionPort
    states: StateSource
    robot: RobotModel
    controller: ControllerModel
    _: KW_ONLY
    clock: ClientClock = REAL_TIME
    state_stall_s: float = DEFAULT_STATE_STALL_S
    """Seconds of state-stream silence after which :meth:`execute` stops the move
    (STOP_MOTION) and raises :class:`StateStreamLostError` (see ``client.watchdog``)."""
    busy_policy: BusyPolicy = BusyPolicy.PACED
    """When each point is first offered (BUSY handling, see :class:`BusyPolicy`)."""
    _stalled_for: float | None = field(default=None, init=False)
    _motion_gone: bool = field(default=False, init=False)
    _in_flight: int | None = field(default=None, init=False)
    """Sequence of the point sent and not yet answered, while there is one."""
    last_stop: EarlyStop | None = field(default=None, init=False)
    """How the latest :meth:`execute` that ended early stopped the robot (None: it did not)."""

    # ------------------------------------------------------------------ sending

    def _refusal(
        self,
        reply: MotoMotionReply,
        index: int,
        point: TrajectoryPoint,
        models: Sequence[GroupModel],
    ) -> ReplyError:
        devs: list[AxisDeviation] = []
        detail = ""
        if reply.result == ResultCode.INVALID and reply.subcode == InvalidSubcode.DATA_START_POS:
            groups = [self.robot.groups.index(m) for m in models]
            current = _joined_positions(self.states.state, groups)
            devs = start_deviations(point, models, current, self.controller)
            detail = (
                _deviation_text(devs, "start", models) or "compared with the commanded position"
            )
        elif reply.result == ResultCode.INVALID and reply.subcode == InvalidSubcode.DATA_SPEED:
            devs = speed_deviations(point, models, self.controller)
            detail = _deviation_text(devs, "speed", models)
        return reply_error(
            reply.result, reply.subcode, reply.command, point=index, detail=detail, deviations=devs
        )

    async def send_point(
        self,
        message: JointTrajPtFull | MotoJointTrajPtFullEx,
        *,
        busy_timeout_s: float,
        stats: StreamStats,
        pacing: _Pacing | None = None,
    ) -> MotoMotionReply:
        """Send one point, retrying BUSY; returns the final (non-BUSY) reply.

        With ``pacing`` (what is known to be queued ahead of the robot), the first offer
        waits until MotoROS can take it (:meth:`_Pacing.first_wait`, unless
        :attr:`busy_policy` is IMMEDIATE), and a retry waits longer while plenty of
        motion is buffered; otherwise it backs off from 0.5 ms.
        """
        clock = self.clock
        backoff = BUSY_BACKOFF_FIRST_S
        first_busy: float | None = None
        if pacing is not None and self.busy_policy is BusyPolicy.PACED:
            wait = pacing.first_wait(clock.now())
            if wait > 0.0:
                await clock.sleep(wait)
        while True:
            lost = self.states.error
            if lost is not None:  # the state stream is gone: the move could not be watched
                raise ConnectionLostError(str(lost))
            if self._stalled_for is not None:  # never send a point blind
                raise _StreamStalledError
            self._in_flight = message.sequence
            if pacing is not None:
                pacing.sent_at = clock.now()
            reply = await self.port.request_motion(message)
            self._in_flight = None
            if reply.result != ResultCode.BUSY:
                if first_busy is not None:
                    stats.max_busy_wait_s = max(stats.max_busy_wait_s, clock.now() - first_busy)
                return reply
            stats.busy_replies += 1
            now = clock.now()
            if first_busy is None:
                first_busy = now
            elif now - first_busy > busy_timeout_s:
                stats.max_busy_wait_s = max(stats.max_busy_wait_s, now - first_busy)
                return reply
            relaxed = 0.0 if pacing is None else pacing.relaxed_wait(now)
            if relaxed > backoff:
                await clock.sleep(relaxed)
                continue
            await clock.sleep(backoff)
            backoff = min(backoff * 2, BUSY_BACKOFF_MAX_S)

    async def send_points(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        *,
        busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S,
        check_speed: bool = True,
        on_accepted: Callable[[int], None] | None = None,
    ) -> StreamStats:
        """Stream every point of ``trajectory`` (joints of ``groups`` concatenated, in order)."""
        models = [self.robot.groups[g] for g in groups]
        sizes = [m.num_axes for m in models]
        stats = StreamStats()
        started = self.clock.now()
        pacing: _Pacing | None = None
        screen = speed_screen(models, self.controller) if check_speed else ()
        for index, point in enumerate(trajectory.points):
            # The screen passes only points the full check would pass without a word.
            if check_speed and not within_screen(point.velocities, screen):
                devs = speed_deviations(point, models, self.controller)
                if devs:
                    raise reply_error(
                        ResultCode.INVALID,
                        InvalidSubcode.DATA_SPEED,
                        _message_type(groups),
                        point=index,
                        detail=_deviation_text(devs, "speed", models) + "; checked before sending",
                        deviations=devs,
                    )
            message = build_message(point, index, groups, sizes)
            reply = await self.send_point(
                message, busy_timeout_s=busy_timeout_s, stats=stats, pacing=pacing
            )
            if reply.result == ResultCode.BUSY:
                raise reply_error(
                    reply.result,
                    reply.subcode,
                    reply.command,
                    point=index,
                    detail=f"BUSY for {busy_timeout_s:g} s after {stats.busy_replies} retries",
                )
            if reply.result != ResultCode.SUCCESS:
                raise self._refusal(reply, index, point, models)
            stats.points += 1
            if pacing is None:
                period = self.controller.interpolation_period_ms / 1000.0
                pacing = _Pacing(self.clock.now(), point.time, period=period)
            else:
                pacing.accepted(point.time)
            if on_accepted is not None:
                on_accepted(index)
        stats.elapsed_s = self.clock.now() - started
        return stats

    # ------------------------------------------------------------------ watching

    async def wait_until_at_rest(
        self, groups: Sequence[int], *, timeout_s: float = 10.0
    ) -> tuple[float, ...]:
        """Wait until ``in_motion`` is false and the feedback is still; return its positions.

        This is "start from current": MotoROS checks point 0 against the commanded
        position with a 30-pulse tolerance, and right after a move, eco mode or a brake
        release the feedback still moves (users meet 3011 here).
        """
        states = self.states
        rest = _RestDetector(groups)
        deadline = self.clock.now() + timeout_s
        try:
            # The loop's timeout bounds a silent stream; the clock's deadline bounds a
            # robot that keeps moving (both: a twin in virtual time keeps its meaning).
            async with asyncio.timeout(timeout_s):
                state = states.state
                while True:
                    pos = _joined_positions(state, groups)
                    if rest.update(state) and pos is not None:
                        return pos
                    if self.clock.now() > deadline:
                        raise TimeoutError
                    state = await states.next_state()
        except TimeoutError:
            status = states.state.status
            raise MotionTimeoutError(
                f"the robot did not come to rest within {timeout_s:g} s "
                f"(in_motion={None if status is None else status.in_motion})"
            ) from None

    async def wait_for_completion(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        monitor: FollowingMonitor,
        *,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        settle_timeout_s: float = DEFAULT_SETTLE_TIMEOUT_S,
        timeout_s: float | None = None,
    ) -> tuple[float, ...]:
        """Wait until the queue is empty, ``in_motion`` false and the feedback settled at the goal.

        Past ``duration + settle_timeout_s`` the wait goes on while the robot still makes
        progress (a safety speed limit slows it, it has not stopped) and fails when it
        stalls for :data:`STALL_TIMEOUT_S` or passes ``timeout_s`` (default: 10 × duration
        + 30 s). A robot that stops because motion became impossible (E-stop, HOLD, alarm)
        raises :class:`NotReadyError` with the controller's reason.
        """
        states = self.states
        port = self.port
        clock = self.clock
        goal = trajectory.goal
        start = clock.now()
        soft_deadline = start + trajectory.duration + settle_timeout_s
        hard_deadline = start + (
            timeout_s if timeout_s is not None else 10 * trajectory.duration + 30
        )
        rest = _RestDetector(groups)
        progress_of = _Progress(trajectory)
        models = [self.robot.groups[g] for g in groups]
        best_progress, best_at = -1.0, start
        state = states.state
        while True:
            now = clock.now()
            positions = _joined_positions(state, groups)
            status = state.status
            if positions is not None and status is not None:
                err = max(abs(p - g) for p, g in zip(positions, goal, strict=True))
                progress = progress_of(positions)
                if progress > best_progress + 1e-4:
                    best_progress, best_at = progress, now
                at_rest = rest.update(state)
                if at_rest and err <= goal_tolerance:
                    counts = [await port.queue_count(g) for g in groups]
                    if not any(counts):
                        return positions
                if not status.motion_possible:
                    readiness = await port.check_motion_ready()
                    if not readiness.ready and err > goal_tolerance:
                        raise reply_error(
                            ResultCode.FALSE,
                            readiness.subcode,
                            MotionCommand.CHECK_MOTION_READY,
                            detail=f"the robot stopped {farthest_text(positions, goal, models)} "
                            "from the goal",
                        )
                past_end = now > start + trajectory.duration + 1.0
                if at_rest and past_end and now - best_at > STALL_TIMEOUT_S:
                    raise MotionIncompleteError(
                        f"the robot came to rest {farthest_text(positions, goal, models)} "
                        f"from the goal, at {joint_values_text(positions, models)}, and is not "
                        "moving (was the motion stopped: STOP_MOTION from this client, HOLD or "
                        "the queue cleared?)"
                    )
            if now > hard_deadline or (now > soft_deadline and now - best_at > STALL_TIMEOUT_S):
                lag = monitor.report.max_lag_s
                raise MotionTimeoutError(
                    f"the move did not finish: planned {trajectory.duration:.2f} s, waited "
                    f"{now - start:.2f} s, progress {max(best_progress, 0.0):.0%}, largest lag "
                    f"{lag:.2f} s"
                )
            state = await states.next_state()

    # ------------------------------------------------------------------ a whole move

    async def execute(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        options: ExecuteOptions = ExecuteOptions(),
    ) -> MoveResult:
        """Stream ``trajectory``, follow the robot, and wait until it settled at the goal.

        Whatever ends the move early (a cancellation, a timeout around it, an exception of
        ``on_progress``, a refusal or error of the client's own) first stops the robot
        (:meth:`stop_early`: STOP_MOTION, then the feedback at rest, within
        :data:`EARLY_STOP_BOUND_S`), then goes on with the position where the robot stopped
        in its message (a note and a log for a ``CancelledError``, which stays one).
        """
        groups = tuple(groups)
        task = asyncio.current_task()
        failed: list[Exception] = []
        """An exception of the caller's progress callback: the move ends with it."""
        on_sample = options.on_progress
        if on_sample is not None:
            on_sample = _callback_guard(on_sample, failed, task)
        monitor = FollowingMonitor(trajectory, groups, on_sample=on_sample, clock=self.clock)
        remove = self.states.add_listener(monitor.listen)
        started = self.clock.now()
        accepted_count = 0
        waiting = False
        cancel_later: list[asyncio.TimerHandle] = []
        self._stalled_for = None
        self._in_flight = None
        self.last_stop = None

        def accepted(index: int) -> None:
            nonlocal accepted_count
            accepted_count = index + 1
            if index == 1:
                monitor.start()

        def on_stall(silence: float) -> None:
            # While sending, the next point is simply not sent (a point in flight keeps its
            # reply, so the count of accepted points stays exact); while waiting, the wait
            # is cancelled.
            self._stalled_for = silence
            if task is None:
                return
            if waiting:
                task.cancel()
            else:  # a point whose reply never comes (the motion port went quiet too)
                grace = asyncio.get_running_loop().call_later(STOP_TIMEOUT_S, task.cancel)
                cancel_later.append(grace)

        watchdog = StallWatchdog(self.states, self.state_stall_s, on_stall, clock=self.clock)

        def disarm() -> None:
            # Before any stop: the callback and the monitor see no sample of it (a
            # callback raising then would turn the move's error into a cancellation,
            # and the monitor would blame FSU/HOLD for a robot the library stops).
            remove()  # idempotent: disarm runs again in ``finally``
            watchdog.close()
            for handle in cancel_later:
                handle.cancel()

        try:
            stats = await self.send_points(
                trajectory,
                groups,
                busy_timeout_s=options.busy_timeout_s,
                check_speed=options.check_speed,
                on_accepted=accepted,
            )
            accepted_count = stats.points
            monitor.start()
            waiting = True
            final = await self.wait_for_completion(
                trajectory,
                groups,
                monitor,
                goal_tolerance=options.goal_tolerance,
                timeout_s=options.timeout_s,
            )
        except _StreamStalledError:
            disarm()  # nothing may cancel the stop below
            raise await self._lost_shielded(
                groups, self._stalled_for, accepted_count, trajectory
            ) from None
        except asyncio.CancelledError as cancel:
            disarm()
            if task is not None and self._stalled():  # the watchdog's cancel, not a caller's
                task.uncancel()
                lost = await self._lost_shielded(
                    groups, self._stalled_for, accepted_count, trajectory
                )
                if task.cancelling():  # the caller cancelled too: that goes on
                    raise asyncio.CancelledError(str(lost)) from lost
                raise lost from None
            if failed and task is not None:  # the progress callback raised: end with it
                task.uncancel()
                error = failed[0]
                await self._stop_then(groups, error, "the progress callback raised")
                if task.cancelling():  # the caller cancelled too: that goes on
                    stop = self.last_stop
                    raise asyncio.CancelledError(stop.text if stop else "") from error
                raise error from None
            reason = f" ({cancel.args[0]})" if cancel.args and cancel.args[0] else ""
            await self._stop_then(groups, cancel, f"the move was cancelled{reason}")
            raise
        except ConnectionLostError as exc:
            if isinstance(exc, StateStreamLostError):
                raise
            if self.states.error is None:  # the motion port went: nothing can be stopped
                disarm()
                if accepted_count or self._in_flight is not None:
                    raise self._motion_lost(exc, groups, accepted_count, trajectory) from exc
                raise
            disarm()
            lost = await self._lost_shielded(groups, None, accepted_count, trajectory)
            if not lost.stopped and self._motion_gone:
                raise  # both went together (the controller closed): the plain loss says it
            raise lost from exc
        except BaseException as exc:  # a refusal, a timeout, KeyboardInterrupt in this thread
            disarm()
            if accepted_count:  # points are queued: the robot may move
                await self._stop_then(groups, exc, f"the move ended early ({type(exc).__name__})")
            raise
        finally:
            disarm()
        return MoveResult(
            trajectory, final, stats, monitor.report, self.clock.now() - started, groups
        )

    async def _stop_then(self, groups: Sequence[int], exc: BaseException, why: str) -> None:
        """:meth:`stop_early`, safe from further cancels, and ``exc`` told where it ended.

        The stop runs as a task of its own, awaited through :func:`asyncio.shield`: a
        second cancel (a ``wait_for`` around a ``wait_for``, a second Ctrl-C) does not cut
        it short; it is remembered, and a ``CancelledError`` goes on once the stop is
        done (at most :data:`EARLY_STOP_BOUND_S` later), so nothing is left half-done.
        """
        # The client's own errors carry the stop in their message: no second line in a log.
        level = logging.INFO if isinstance(exc, ClientError) else logging.WARNING
        outcome, cancelled_again = await _shielded(self.stop_early(groups, why, quiet_level=level))
        self.last_stop = outcome
        outcome.tell(exc)
        if cancelled_again and not isinstance(exc, asyncio.CancelledError):
            raise asyncio.CancelledError(outcome.text) from exc

    async def _lost_shielded(
        self,
        groups: Sequence[int],
        silent_s: float | None,
        accepted: int,
        trajectory: JointTrajectory,
    ) -> StateStreamLostError:
        """:meth:`_stream_lost` safe from further cancels, as :meth:`_stop_then`: a cancel
        meanwhile goes on as a ``CancelledError`` (from the loss) once STOP_MOTION went."""
        lost, cancelled_again = await _shielded(
            self._stream_lost(groups, silent_s, accepted, trajectory)
        )
        if cancelled_again:
            raise asyncio.CancelledError(str(lost)) from lost
        return lost

    async def stop_early(
        self, groups: Sequence[int], why: str, *, quiet_level: int = logging.WARNING
    ) -> EarlyStop:
        """Stop the robot after a move ended early: STOP_MOTION, then wait (at most
        :data:`STOP_REST_TIMEOUT_S`) until the feedback shows it at rest.

        Never raises for a stop that fails: the :class:`EarlyStop` says what happened,
        with the last known position and "stop the robot on the pendant" (logged as an
        error). A stop that worked is logged at ``quiet_level``: a warning where only a
        note carries it (a cancellation), INFO where the error's own message does.
        """
        started = self.clock.now()
        stopped, note = await self._send_stop(groups)
        at_rest = False
        rest_note = ""
        if stopped:
            try:
                await self.wait_until_at_rest(groups, timeout_s=STOP_REST_TIMEOUT_S)
                at_rest = True
            except ClientError as exc:  # a timeout, the state stream gone
                rest_note = f"; the feedback did not show it at rest ({exc})"
        models = [self.robot.groups[g] for g in groups]
        positions = _joined_positions(self.states.state, groups) or ()
        where = joint_values_text(positions, models)
        took = self.clock.now() - started
        if at_rest:
            detail = f"the robot was stopped (STOP_MOTION) and stands at {where}"
            logger.log(
                quiet_level,
                "%s: %s (at rest %.3f s after the stop was sent)",
                why,
                detail,
                took,
                extra=AS_STOP_REPORT,
            )
        else:
            detail = f"{note}{rest_note}; last known position {where}"
            if stopped:
                detail += ": check that the robot stands, stop it on the pendant if not"
            logger.error("%s: %s", why, detail)
        return EarlyStop(stopped, at_rest, positions, took, why, detail)

    async def _send_stop(self, groups: Sequence[int]) -> tuple[bool, str]:
        """STOP_MOTION within :data:`STOP_TIMEOUT_S`: (acknowledged, what happened). The one
        place that words a failed stop ("stop the robot on the pendant")."""
        self._motion_gone = False
        try:
            reply = await self.port.request_motion(
                MotoMotionCtrl(groups[0], 0, int(MotionCommand.STOP_MOTION)),
                timeout_s=STOP_TIMEOUT_S,
            )
        except (ConnectionLostError, RequestTimeoutError) as exc:
            self._motion_gone = isinstance(exc, ConnectionLostError)
            return False, f"STOP_MOTION could not be sent ({exc}): {STOP_ON_THE_PENDANT}"
        except ClientError as exc:
            return False, f"STOP_MOTION failed ({exc}): {STOP_ON_THE_PENDANT}"
        if reply.result == ResultCode.SUCCESS:
            return True, "STOP_MOTION acknowledged"
        return False, (
            f"STOP_MOTION refused (result {reply.result}, subcode {reply.subcode}): "
            f"{STOP_ON_THE_PENDANT}"
        )

    def forget_stop(self) -> None:
        """A new move starts: :attr:`last_stop` is no longer about it."""
        self.last_stop = None

    def _stalled(self) -> bool:
        """Has the watchdog tripped during the current :meth:`execute`? (set by its callback)"""
        return self._stalled_for is not None

    async def _stream_lost(
        self,
        groups: Sequence[int],
        silent_s: float | None,
        accepted: int,
        trajectory: JointTrajectory,
    ) -> StateStreamLostError:
        """Stop the robot (STOP_MOTION, if the motion port still answers) and say what was lost."""
        stopped, stop_note = await self._send_stop(groups)
        positions, where = self._last_known(groups)
        if silent_s is None:
            what = f"the state stream closed ({self.states.error})"
        else:
            what = (
                f"the state stream stalled: no state message for {silent_s:.2f} s "
                f"(bound {self.state_stall_s:g} s)"
            )
        total = len(trajectory.points)
        unanswered = (
            ""
            if self._in_flight is None
            else f" (point {self._in_flight} was sent and never answered: it may be queued too)"
        )
        message = (
            f"{what}; streaming stopped with {accepted} of {total} points accepted by the "
            f"robot{unanswered}; {stop_note}; last known position {where}. Check the network "
            "to the "
            "controller, then reconnect and move again from the current position"
        )
        logger.error("%s", message)
        return StateStreamLostError(
            message,
            silent_s=silent_s,
            positions=positions,
            accepted_points=accepted,
            total_points=total,
            stopped=stopped,
        )

    def _last_known(self, groups: Sequence[int]) -> tuple[tuple[float, ...], str]:
        """The last position the state stream reported and its text with units
        ("unknown" without one): what every error after a lost connection quotes."""
        positions = _joined_positions(self.states.state, groups) or ()
        if not positions:
            return (), "unknown"
        return positions, joint_values_text(positions, [self.robot.groups[g] for g in groups])

    def _motion_lost(
        self,
        exc: ConnectionLostError,
        groups: Sequence[int],
        accepted: int,
        trajectory: JointTrajectory,
    ) -> MotionConnectionLostError:
        """The motion connection went mid-move while the state stream lives: MotoROS
        goes on with its queue (§2.2) and nothing can stop it from here."""
        positions, where = self._last_known(groups)
        total = len(trajectory.points)
        message = (
            f"{exc}; streaming stopped with {accepted} of {total} points accepted by the "
            "robot: the points already queued may still run (MotoROS goes on with its queue "
            "after the motion connection closes, reference §2.2) and STOP_MOTION cannot be "
            f"sent without it: {STOP_ON_THE_PENDANT}; last known position {where}"
        )
        logger.error("%s", message)
        return MotionConnectionLostError(
            message, positions=positions, accepted_points=accepted, total_points=total
        )


_T = TypeVar("_T")


async def _shielded(work: Coroutine[object, object, _T]) -> tuple[_T, bool]:
    """Run ``work`` as a task of its own, awaited through :func:`asyncio.shield` until it
    is done: (its result, whether the caller was cancelled meanwhile). A stop that a
    second cancel (a ``wait_for`` around a ``wait_for``, a second Ctrl-C) cut short
    would leave the robot moving; the caller re-raises the cancel once it is done."""
    running = asyncio.ensure_future(work)
    cancelled_again = False
    while True:
        try:
            return await asyncio.shield(running), cancelled_again
        except asyncio.CancelledError:
            cancelled_again = True
            if running.done():  # cancelled as it finished: keep what it did
                if running.cancelled():  # the loop itself is going away
                    raise
                return running.result(), cancelled_again


def _callback_guard(
    callback: Callable[[FollowingSample], None],
    failed: list[Exception],
    task: asyncio.Task[object] | None,
) -> Callable[[FollowingSample], None]:
    """``callback`` for the following monitor: its first exception is kept in ``failed``
    and cancels the move's task (the move then stops the robot and raises it); later
    samples are not passed on."""

    def guarded(sample: FollowingSample) -> None:
        if failed:
            return
        try:
            callback(sample)
        except Exception as exc:
            failed.append(exc)
            if task is not None:
                task.cancel()

    return guarded


def joint_values_text(
    positions: Sequence[float], models: Sequence[GroupModel], *, deg: bool = False
) -> str:
    """``[0.5724, 0.0000, …] rad`` (``rad``/``m`` after each value when a linear axis is
    among them; ``deg`` for the rotary axes with ``deg``): joint values with their
    units, as every message of the client gives them."""
    axes = [a for m in models for a in m.axes]
    rotary = "deg" if deg else "rad"

    def value(v: float, linear: bool) -> str:
        return f"{v if linear or not deg else math.degrees(v):.4f}"

    if len(axes) != len(positions):
        return "[" + ", ".join(f"{v:.4f}" for v in positions) + "] (rad/m)"
    if not any(a.linear for a in axes):
        return "[" + ", ".join(value(v, False) for v in positions) + f"] {rotary}"
    return (
        "["
        + ", ".join(
            f"{value(v, a.linear)} {'m' if a.linear else rotary}"
            for v, a in zip(positions, axes, strict=True)
        )
        + "]"
    )


def farthest_text(
    positions: Sequence[float], goal: Sequence[float], models: Sequence[GroupModel]
) -> str:
    """The largest joint distance to ``goal`` with its unit and joint: ``0.1056 rad
    (joint_1_s)``, as every message that says how far the robot is from a goal gives it."""
    axes = [a for m in models for a in m.axes]
    gaps = [abs(p - g) for p, g in zip(positions, goal, strict=True)]
    if not gaps:
        return "0 rad"
    i = max(range(len(gaps)), key=gaps.__getitem__)
    if len(axes) != len(gaps):
        return f"{gaps[i]:.4f} rad/m (axis {i + 1})"
    return f"{gaps[i]:.4f} {'m' if axes[i].linear else 'rad'} ({axes[i].name})"


class _StreamStalledError(Exception):
    """Internal: the watchdog saw the state stream stall while points were being sent."""


def _message_type(groups: Sequence[int]) -> int:
    return int(
        MsgType.JOINT_TRAJ_PT_FULL if len(groups) == 1 else MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    )


class FollowingMonitor:
    """Compares feedback with the planned trajectory while it runs.

    Call :meth:`start` when the robot is told to move; it then listens to the state
    stream. :attr:`report` holds the worst lag and error seen; ``on_sample`` gets every
    :class:`FollowingSample` (a progress bar, a log, a plot).
    """

    def __init__(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        *,
        warn_lag_s: float = LAG_WARNING_S,
        on_sample: Callable[[FollowingSample], None] | None = None,
        clock: ClientClock = REAL_TIME,
    ) -> None:
        self.trajectory = trajectory
        self.clock = clock
        self.groups = tuple(groups)
        self.warn_lag_s = warn_lag_s
        self.on_sample = on_sample
        self.report = FollowingReport()
        self.last: FollowingSample | None = None
        self._t0: float | None = None
        # Per-point times and progress, computed once: every state message (40 Hz) looks
        # the plan up, and a minute-long plan has thousands of points.
        self._progress = _Progress(trajectory)
        points = trajectory.points
        self._times = [p.time for p in points]
        self._raw = [self._progress(p.positions) for p in points]
        self._best: list[float] = list(itertools.accumulate(self._raw[1:], max))
        self._recent: collections.deque[tuple[float, float]] = collections.deque()
        """(elapsed, plan time reached) of the samples in the last SPEED_WINDOW_S."""
        self._previous = 0.0
        """Elapsed time of the previous sample (for the gaps between state messages)."""

    def start(self, t0: float | None = None) -> None:
        if self._t0 is None:
            self._t0 = self.clock.now() if t0 is None else t0

    @property
    def started(self) -> bool:
        return self._t0 is not None

    def listen(self, state: RobotState) -> None:
        """State listener form of :meth:`update`."""
        self.update(state)

    def update(self, state: RobotState) -> FollowingSample | None:
        if self._t0 is None:
            return None
        positions = _joined_positions(state, self.groups)
        if positions is None:
            return None
        elapsed = self.clock.now() - self._t0
        planned = self._planned_at(elapsed)
        # max/min of two values spelled as the comparisons the builtins make (the first
        # argument wins ties and NaN), without a builtin call each: 40 samples a second.
        error = max(map(abs, map(operator.sub, positions, planned)), default=0.0)
        raw = self._progress(positions)
        raw = 0.0 if raw < 0.0 else raw
        progress = 1.0 if raw > 1.0 else raw
        reached = self._time_at_progress(progress)
        # Within 0.1 % of the goal the robot is there: its last pulses of settling are no lag.
        behind = elapsed - reached
        lag = (behind if behind > 0.0 else 0.0) if progress < ARRIVED_PROGRESS else 0.0
        speed_pct = self._speed_pct(elapsed, reached, progress)
        sample = FollowingSample(elapsed, progress, lag, error, speed_pct)
        rep = self.report
        rep.samples += 1
        gap = elapsed - self._previous
        self._previous = elapsed
        if gap > rep.max_state_gap_s:
            rep.max_state_gap_s = gap
        if error > rep.max_error:
            rep.max_error = error
        if lag > rep.max_lag_s:
            rep.max_lag_s = lag
        if speed_pct < rep.min_speed_pct:
            rep.min_speed_pct = speed_pct
        if lag > self.warn_lag_s and not rep.reason:
            self._blame(state, sample, reached)
        self.last = sample
        if self.on_sample is not None:
            self.on_sample(sample)
        return sample

    def _blame(self, state: RobotState, sample: FollowingSample, reached: float) -> None:
        """Say once why the robot fell behind: slowed (the speed it reports is below the
        plan's) or a late controller/network (it reports the planned speed, or the state
        messages came late), with the numbers used."""
        rep = self.report
        reported = self._reported_pct(state, reached)
        gap_ms = rep.max_state_gap_s * 1000
        head = (
            f"the robot runs {sample.lag_s:.2f} s ({sample.error:.4f} rad) behind the plan at "
            f"{sample.progress:.0%} of the move"
        )
        numbers = (
            f"over the last {SPEED_WINDOW_S:g} s it gained {sample.speed_pct:.0f} % of the "
            f"plan's time per second of the client's clock; state messages up to "
            f"{gap_ms:.0f} ms apart (MotoROS sends a cycle every {STATE_PERIOD_S * 1000:.0f} ms)"
        )
        if reported is not None and reported < SLOWED_SPEED_PCT:
            rep.slowed = True
            rep.reason = (
                f"{head}: it reports moving at {reported:.0f} % of the planned speed (its "
                f"feedback velocity; {numbers}): the controller is slowing it: a safety "
                "speed limit (FSU), a speed override or HOLD"
            )
        elif reported is not None or rep.max_state_gap_s > LATE_STATE_GAP_S:
            rep.late = True
            told = (
                ""
                if reported is None
                else f", yet it reports moving at {reported:.0f} % of the planned speed"
            )
            rep.reason = (
                f"{head}{told}: the controller or the network is late, the robot is not "
                f"slowed ({numbers}): a loaded or stalled simulator loop, or a slow network"
            )
        elif sample.speed_pct < SLOWED_SPEED_PCT:  # no velocity in the feedback
            rep.slowed = True
            rep.reason = (
                f"{head}, progressing at {sample.speed_pct:.0f} % of the planned speed "
                f"({numbers}; the feedback carries no velocity): a safety speed limit (FSU), "
                "a speed override or HOLD is slowing it"
            )
        else:
            rep.reason = (
                f"{head}, though it now progresses at {sample.speed_pct:.0f} % of the planned "
                f"speed ({numbers}; the feedback carries no velocity): it was held up earlier"
            )
        logger.warning("%s", rep.reason, extra=AS_NOTE)  # the CLI: a `note: …` line

    def _reported_pct(self, state: RobotState, reached: float) -> float | None:
        """The robot's own velocity report along the plan's velocity where it stands, in %
        of the planned speed (None: no velocity in the feedback, or the plan stands)."""
        velocities: list[float] = []
        for g in self.groups:
            joint = state.joints.get(g)
            if joint is None or joint.velocities is None:
                return None
            velocities.extend(joint.velocities)
        planned = self._planned_velocity_at(reached)
        norm = sum(v * v for v in planned)
        if norm <= _STILL_PLAN or len(planned) != len(velocities):
            return None
        return 100.0 * sum(a * b for a, b in zip(velocities, planned, strict=True)) / norm

    def _planned_velocity_at(self, t: float) -> tuple[float, ...]:
        """The plan's joint velocities at ``t`` (linear between the points' velocities)."""
        pts = self.trajectory.points
        i = bisect.bisect_right(self._times, t) - 1
        if i < 0:
            return pts[0].velocities
        if i >= len(pts) - 1:
            return pts[-1].velocities
        a, b = pts[i], pts[i + 1]
        h = b.time - a.time
        s = 0.0 if h <= 0 else (t - a.time) / h
        return tuple(va + s * (vb - va) for va, vb in zip(a.velocities, b.velocities, strict=True))

    def _speed_pct(self, elapsed: float, reached: float, progress: float) -> float:
        """Plan time gained per second over the last window, in % (100 outside motion)."""
        recent = self._recent
        recent.append((elapsed, reached))
        while recent and elapsed - recent[0][0] > SPEED_WINDOW_S:
            recent.popleft()
        t0, r0 = recent[0]
        end = self._times[-1] if self._times else 0.0
        if elapsed - t0 < SPEED_WINDOW_S / 2 or progress >= ARRIVED_PROGRESS or r0 >= end:
            return 100.0
        return max(0.0, 100.0 * (reached - r0) / (elapsed - t0))

    def _planned_at(self, t: float) -> tuple[float, ...]:
        """``trajectory.position_at(t)``, finding the segment by bisection.

        Inside a segment (``a.time <= t < b.time``, every ordered plan) the cubic of
        :meth:`JointTrajectory.position_at` is evaluated here with the very same float
        operations, in the same order, so the result is bit for bit the same without a
        two-point trajectory built per state message.
        """
        pts = self.trajectory.points
        if t <= 0.0 or len(pts) == 1:
            return pts[0].positions
        if t >= pts[-1].time:
            return pts[-1].positions
        i = bisect.bisect_right(self._times, t) - 1
        if i < 0:  # a plan whose first point is not at 0: as the trajectory has it
            return self.trajectory.position_at(t)
        a, b = pts[i], pts[i + 1]
        if not a.time <= t < b.time:  # a plan whose times do not increase: as before
            return JointTrajectory((a, b), b.time).position_at(t)
        h = b.time - a.time
        s = (t - a.time) / h
        s2 = s**2
        s3 = s**3
        h00 = 2 * s3 - 3 * s2 + 1
        h10 = s3 - 2 * s2 + s
        h01 = -2 * s3 + 3 * s2
        h11 = s3 - s2
        k10 = h10 * h  # ``h10 * h * v0`` is ``(h10 * h) * v0``: the same product
        k11 = h11 * h
        return tuple(
            [  # a list, not a generator: one frame instead of one resumption per joint
                h00 * p0 + k10 * v0 + h01 * p1 + k11 * v1
                for p0, v0, p1, v1 in zip(
                    a.positions, a.velocities, b.positions, b.velocities, strict=True
                )
            ]
        )

    def _time_at_progress(self, fraction: float) -> float:
        """``trajectory.time_at_progress(fraction)``, by bisection on the running best."""
        if fraction <= 0.0:
            return 0.0
        pts = self.trajectory.points
        k = bisect.bisect_left(self._best, fraction)
        if k >= len(self._best):
            return pts[-1].time
        i = k + 1  # index in points (the running best starts at point 1)
        f = self._raw[i]
        prev_t, prev_f = (0.0, 0.0) if i == 1 else (pts[i - 1].time, self._raw[i - 1])
        if f <= prev_f:
            return pts[i].time
        return prev_t + (fraction - prev_f) / (f - prev_f) * (pts[i].time - prev_t)


class _Progress:
    """``trajectory.progress`` with the start-to-goal line computed once.

    A plan that comes to rest on the way (a detour around an obstacle,
    :mod:`pymotoros.client.avoid`: straight segments, rest to rest) is measured along the
    polyline through its rest points instead, by length, on the segment nearest the
    position: its start-to-goal line says nothing of a robot going round."""

    __slots__ = ("_dd", "_direction", "_segments", "_size", "_start", "_total")

    def __init__(self, trajectory: JointTrajectory) -> None:
        self._start = trajectory.start
        self._direction = [g - s for g, s in zip(trajectory.goal, trajectory.start, strict=True)]
        self._dd = sum(x * x for x in self._direction)
        self._size = len(self._start)
        corners = [trajectory.start]
        for p in trajectory.points[1:-1]:
            if not any(p.velocities) and p.positions != corners[-1]:
                corners.append(p.positions)
        if trajectory.goal != corners[-1]:
            corners.append(trajectory.goal)
        self._segments: list[tuple[tuple[float, ...], list[float], float, float, float]] = []
        """Per segment between rest points: start, direction, its square, length so far,
        length (empty for a plan with no rest on the way)."""
        self._total = 0.0
        if corners[1:-1]:  # a rest on the way: more than the start and the goal
            for a, b in itertools.pairwise(corners):
                d = [y - x for x, y in zip(a, b, strict=True)]
                dd = sum(x * x for x in d)
                self._segments.append((a, d, dd, self._total, dd**0.5))
                self._total += dd**0.5

    def __call__(self, positions: Sequence[float]) -> float:
        if self._segments:
            return self._along_polyline(positions)
        if self._dd <= _SAME_POSITION:
            return 1.0
        if len(positions) == self._size:
            # The same products summed by the same ``sum`` in the same order as below,
            # through ``map`` instead of a generator (once per state message).
            total: float = sum(
                map(operator.mul, map(operator.sub, positions, self._start), self._direction)
            )
            return total / self._dd
        return (  # different lengths: zip's strict error, as always
            sum(
                (p - s) * x for p, s, x in zip(positions, self._start, self._direction, strict=True)
            )
            / self._dd
        )

    def _along_polyline(self, positions: Sequence[float]) -> float:
        best_distance, best = float("inf"), 0.0
        for a, d, dd, before, length in self._segments:
            rel = [p - x for p, x in zip(positions, a, strict=True)]
            t = min(1.0, max(0.0, sum(r * x for r, x in zip(rel, d, strict=True)) / dd))
            distance = sum((r - t * x) ** 2 for r, x in zip(rel, d, strict=True))
            if distance < best_distance:
                best_distance, best = distance, (before + t * length) / self._total
        return best


class _RestDetector:
    """Counts state cycles (one per ROBOT_STATUS) with ``in_motion`` false and still feedback."""

    def __init__(self, groups: Sequence[int]) -> None:
        self.groups = tuple(groups)
        self.quiet = 0
        self._cycle = -1
        self._prev: tuple[float, ...] | None = None

    def update(self, state: RobotState) -> bool:
        """True once the robot has been at rest for :data:`SETTLE_SAMPLES` cycles."""
        if state.status_count != self._cycle and state.status is not None:
            self._cycle = state.status_count
            pos = _joined_positions(state, self.groups)
            still = (
                pos is not None
                and self._prev is not None
                and all(abs(a - b) <= SETTLE_STEP for a, b in zip(pos, self._prev, strict=True))
            )
            self.quiet = self.quiet + 1 if still and state.status.in_motion is False else 0
            self._prev = pos
        return self.quiet >= SETTLE_SAMPLES
