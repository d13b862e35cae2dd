"""Watching the robot follow a trajectory: :class:`FollowingMonitor` compares the
state stream's feedback with the plan while a move runs, reports how far behind the robot
runs and why (a safety speed limit, HOLD, late feedback), and hands every
:class:`FollowingSample` to the caller's ``on_progress``.
"""

from __future__ import annotations

import bisect
import collections
import itertools
import logging
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Final

from pymotoros.client.planning import JointTrajectory
from pymotoros.client.state import RobotState
from pymotoros.client.timing import REAL_TIME, ClientClock
from pymotoros.log_tags import AS_NOTE

logger = logging.getLogger(__name__)


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


def joined_positions(state: RobotState, groups: Sequence[int]) -> tuple[float, ...] | None:
    values: list[float] = []
    for g in groups:
        pos = state.positions(g)
        if pos is None:
            return None
        values.extend(pos)
    return tuple(values)


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
        self._progress = PathProgress(trajectory)
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
        positions = joined_positions(state, self.groups)
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


class PathProgress:
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
