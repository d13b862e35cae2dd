"""Synchronised point-to-point joint moves, time-optimal under jerk limits, via ruckig.

A move from rest to rest between two joint positions is planned with ruckig
(time-optimal, jerk-limited, every joint finishing together on a straight line in
joint space), then sampled on a uniform time grid into trajectory points with
positions, velocities and accelerations, ready to stream to MotoROS. Why ruckig
and not toppra: see ``docs/client.md``.

Limits come from the robot model: position, velocity (never above the speed
MotoROS itself accepts, §5.5), acceleration and jerk, scaled MoveIt-style by
``velocity_scaling`` and ``acceleration_scaling`` in (0, 1].
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from pymotoros.client.errors import ClientError
from pymotoros.models import AxisModel, FloatMode, GroupModel
from pymotoros.models.rules import axis_speed_limit

DEFAULT_SAMPLE_PERIOD_S: Final = 0.02
"""Default spacing of generated points: 5 interpolation ticks of 4 ms. MotoROS fits a
cubic through each pair of points (§5.4), which follows a jerk-limited profile sampled
this finely to well under a pulse, and 50 points per second leave the motion port idle
most of the time."""

MIN_SAMPLE_PERIOD_S: Final = 0.004
"""Points closer than one interpolation tick give MotoROS segments shorter than a tick."""

MIN_MOVE_DURATION_S: Final = 0.008
"""Shortest move planned (two ticks), so that a tiny move is never a sub-tick segment that
MotoROS would drop silently (§3.4: a point whose time does not advance is dropped)."""

_SAME_POSITION: Final = 1e-12


class PlanningError(ClientError, ValueError):
    """A move cannot be planned: a goal outside the joint limits, bad scaling, a wrong size."""


@dataclass(frozen=True, slots=True)
class JointLimits:
    """Per-joint limits in ROS order (rad, rad/s, rad/s², rad/s³; m for linear axes)."""

    names: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    max_velocity: tuple[float, ...]
    max_acceleration: tuple[float, ...]
    max_jerk: tuple[float, ...]
    linear: tuple[bool, ...] = ()
    """Which joints are linear (m); empty: every joint is rotary (rad). For the units
    of the errors."""

    @classmethod
    def from_group(
        cls,
        group: GroupModel,
        period_ms: int = 4,
        float_mode: FloatMode = FloatMode.X87_EXTENDED,
    ) -> JointLimits:
        """The limits of a model group; velocity capped at MotoROS's own speed check."""
        axes = group.axes
        return cls(
            names=tuple(a.name for a in axes),
            lower=tuple(a.lower for a in axes),
            upper=tuple(a.upper for a in axes),
            max_velocity=tuple(
                min(a.max_velocity, motoros_speed_limit(a, period_ms, float_mode)) for a in axes
            ),
            max_acceleration=tuple(a.max_acceleration for a in axes),
            max_jerk=tuple(a.max_jerk for a in axes),
            linear=tuple(a.linear for a in axes),
        )

    @classmethod
    def concat(cls, parts: Sequence[JointLimits]) -> JointLimits:
        """The limits of several groups moved as one (for JOINT_TRAJ_PT_FULL_EX)."""
        return cls(
            names=tuple(n for p in parts for n in p.names),
            lower=tuple(v for p in parts for v in p.lower),
            upper=tuple(v for p in parts for v in p.upper),
            max_velocity=tuple(v for p in parts for v in p.max_velocity),
            max_acceleration=tuple(v for p in parts for v in p.max_acceleration),
            max_jerk=tuple(v for p in parts for v in p.max_jerk),
            linear=tuple(v for p in parts for v in (p.linear or (False,) * p.dof)),
        )

    @property
    def dof(self) -> int:
        """Number of joints (degrees of freedom) these limits cover."""
        return len(self.names)

    def is_linear(self, i: int) -> bool:
        """Is joint ``i`` linear (m), not rotary (rad)?"""
        return bool(self.linear) and self.linear[i]

    def value_text(self, i: int, value: float) -> str:
        """``3.500000 rad (200.535 deg)`` or ``1.200000 m``: a value of joint ``i`` with its
        unit, as every error of the client gives a distance."""
        if self.is_linear(i):
            return f"{value:.6f} m"
        return f"{value:.6f} rad ({math.degrees(value):.3f} deg)"


def motoros_speed_limit(
    axis: AxisModel, period_ms: int, float_mode: FloatMode = FloatMode.X87_EXTENDED
) -> float:
    """The speed (rad/s) above which MotoROS answers 3013 for this axis (§5.5).

    The controller's own float32 number (:func:`pymotoros.models.rules.axis_speed_limit`):
    maxInc = trunc(pulses/s × period), then trunc(maxInc × 1000 / period) pulses/s,
    converted back to rad/s as the ``float_mode`` build does. Always at or just below
    the datasheet speed. MotoROS's test truncates the velocity first (the pre-flight,
    :mod:`pymotoros.client.preflight`, applies it).
    """
    return axis_speed_limit(axis, period_ms, float_mode)[2]


@dataclass(frozen=True, slots=True)
class TrajectoryPoint:
    """One point as MotoROS takes it: time from the start (s) and per-joint values."""

    time: float
    positions: tuple[float, ...]
    velocities: tuple[float, ...]
    accelerations: tuple[float, ...] = ()


@dataclass(frozen=True, slots=True)
class JointTrajectory:
    """Sampled trajectory; :attr:`optimal_duration` is what ruckig found time-optimal."""

    points: tuple[TrajectoryPoint, ...]
    optimal_duration: float

    @property
    def duration(self) -> float:
        """Planned duration in seconds: the time of the last point."""
        return self.points[-1].time

    @property
    def start(self) -> tuple[float, ...]:
        """Positions of the first point (rad, m for linear axes), in ROS joint order."""
        return self.points[0].positions

    @property
    def goal(self) -> tuple[float, ...]:
        """Positions of the last point (rad, m for linear axes), in ROS joint order."""
        return self.points[-1].positions

    def position_at(self, t: float) -> tuple[float, ...]:
        """Planned positions at time ``t``: the cubic through neighbouring points, as MotoROS."""
        pts = self.points
        if t <= 0.0 or len(pts) == 1:
            return pts[0].positions
        if t >= pts[-1].time:
            return pts[-1].positions
        i = bisect.bisect_right([p.time for p in pts], t) - 1
        a, b = pts[i], pts[i + 1]
        h = b.time - a.time
        s = (t - a.time) / h
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        return tuple(
            h00 * p0 + h10 * h * v0 + h01 * p1 + h11 * h * v1
            for p0, v0, p1, v1 in zip(
                a.positions, a.velocities, b.positions, b.velocities, strict=True
            )
        )

    def progress(self, positions: Sequence[float]) -> float:
        """How far ``positions`` are along the joint-space line from start to goal (0..1)."""
        d = [g - s for g, s in zip(self.goal, self.start, strict=True)]
        dd = sum(x * x for x in d)
        if dd <= _SAME_POSITION:
            return 1.0
        proj = sum((p - s) * x for p, s, x in zip(positions, self.start, d, strict=True))
        return proj / dd

    def time_at_progress(self, fraction: float) -> float:
        """When the plan reaches ``fraction`` of the way (linear between points)."""
        if fraction <= 0.0:
            return 0.0
        pts = self.points
        prev_t, prev_f = 0.0, 0.0
        for p in pts[1:]:
            f = self.progress(p.positions)
            if f >= fraction:
                if f <= prev_f:
                    return p.time
                return prev_t + (fraction - prev_f) / (f - prev_f) * (p.time - prev_t)
            prev_t, prev_f = p.time, f
        return pts[-1].time


def check_scaling(name: str, value: float) -> None:
    """Refuse a speed or acceleration scale outside (0, 1] (``name`` says which)."""
    if not 0.0 < value <= 1.0 or math.isnan(value):
        raise PlanningError(f"{name} must be in (0, 1], got {value}")


def ruckig_plan(
    start: Sequence[float],
    goal: Sequence[float],
    vmax: Sequence[float],
    amax: Sequence[float],
    jmax: Sequence[float],
    times: int,
) -> tuple[float, list[tuple[list[float], list[float], list[float]]]]:
    """The one place ruckig (untyped) is called: plan, then sample at ``times`` + 1 instants.

    Returns ruckig's duration and (positions, velocities, accelerations) at k·T/times.
    """
    import ruckig

    dof = len(start)
    inp = ruckig.InputParameter(dof)
    inp.current_position = list(start)
    inp.current_velocity = [0.0] * dof
    inp.current_acceleration = [0.0] * dof
    inp.target_position = list(goal)
    inp.target_velocity = [0.0] * dof
    inp.target_acceleration = [0.0] * dof
    inp.max_velocity = list(vmax)
    inp.max_acceleration = list(amax)
    inp.max_jerk = list(jmax)
    inp.synchronization = ruckig.Synchronization.Phase
    inp.minimum_duration = MIN_MOVE_DURATION_S
    trajectory = ruckig.Trajectory(dof)
    result = ruckig.Ruckig(dof).calculate(inp, trajectory)
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise PlanningError(f"ruckig could not plan the move: {result}")
    duration = float(trajectory.duration)
    samples = []
    for k in range(times + 1):
        p, v, a = trajectory.at_time(duration * k / times)
        samples.append(([float(x) for x in p], [float(x) for x in v], [float(x) for x in a]))
    return duration, samples


def sample_count(duration: float, sample_period: float) -> int:
    """Number of segments: the fewest that keep points at most ``sample_period`` apart,
    but never so many that they come closer than one tick (4 ms)."""
    wanted = math.ceil(duration / sample_period - 1e-9)
    return max(1, min(wanted, math.floor(duration / MIN_SAMPLE_PERIOD_S + 1e-9)))


def plan_joint_move(
    start: Sequence[float],
    goal: Sequence[float],
    limits: JointLimits,
    *,
    velocity_scaling: float = 1.0,
    acceleration_scaling: float = 1.0,
    sample_period: float = DEFAULT_SAMPLE_PERIOD_S,
) -> JointTrajectory:
    """Plan a synchronised rest-to-rest move from ``start`` to ``goal``.

    ``velocity_scaling`` scales every joint's velocity limit and
    ``acceleration_scaling`` its acceleration and jerk limits (as MoveIt's
    ``max_velocity_scaling_factor`` / ``max_acceleration_scaling_factor``). The first
    point is ``start`` at t = 0, the last is ``goal`` at rest; points are evenly
    spaced, at most ``sample_period`` apart (8 ms for very short moves with a 4 ms
    ``sample_period``) and at least 4 ms apart.
    """
    n = limits.dof
    if len(start) != n or len(goal) != n:
        raise PlanningError(
            f"expected {n} joint values ({', '.join(limits.names)}), "
            f"got start {len(start)} and goal {len(goal)}"
        )
    check_scaling("velocity_scaling", velocity_scaling)
    check_scaling("acceleration_scaling", acceleration_scaling)
    if sample_period < MIN_SAMPLE_PERIOD_S:
        raise PlanningError(f"sample_period must be at least {MIN_SAMPLE_PERIOD_S} s")
    for i, g in enumerate(goal):
        if not math.isfinite(g) or not limits.lower[i] <= g <= limits.upper[i]:
            unit = "m" if limits.is_linear(i) else "rad"
            degrees = (
                ""
                if limits.is_linear(i)
                else f" ([{math.degrees(limits.lower[i]):.3f}, "
                f"{math.degrees(limits.upper[i]):.3f}] deg)"
            )
            raise PlanningError(
                f"goal {limits.value_text(i, g)} for {limits.names[i]} is outside its limits "
                f"[{limits.lower[i]:.6f}, {limits.upper[i]:.6f}] {unit}{degrees}; give a goal "
                "within them"
            )
    start_t = tuple(float(x) for x in start)
    goal_t = tuple(float(x) for x in goal)
    zeros = (0.0,) * n
    if all(abs(g - s) <= _SAME_POSITION for g, s in zip(goal_t, start_t, strict=True)):
        return JointTrajectory((TrajectoryPoint(0.0, start_t, zeros, zeros),), 0.0)

    vmax = [v * velocity_scaling for v in limits.max_velocity]
    amax = [a * acceleration_scaling for a in limits.max_acceleration]
    jmax = [j * acceleration_scaling for j in limits.max_jerk]
    # First pass for the duration, second to sample it (ruckig plans in microseconds).
    duration, _ = ruckig_plan(start_t, goal_t, vmax, amax, jmax, 1)
    segments = sample_count(duration, sample_period)
    duration, samples = ruckig_plan(start_t, goal_t, vmax, amax, jmax, segments)

    points = [TrajectoryPoint(0.0, start_t, zeros, zeros)]
    for k in range(1, segments):
        pos, vel, acc = samples[k]
        # Clamp float noise of the solver to the limits so every point passes MotoROS.
        vel = [max(-lim, min(lim, v)) for v, lim in zip(vel, vmax, strict=True)]
        points.append(TrajectoryPoint(duration * k / segments, tuple(pos), tuple(vel), tuple(acc)))
    points.append(TrajectoryPoint(duration, goal_t, zeros, zeros))
    return JointTrajectory(tuple(points), duration)
