"""Waypoints to a timed trajectory within the model's limits (toppra).

Why toppra: it computes the time-optimal parameterisation of a path through many
waypoints under per-joint velocity and acceleration limits, which is what MoveIt's
time parameterisation does. Ruckig (already used for point-to-point moves in
:mod:`pymotoros.client.planning`) passes intermediate waypoints only in its paid
version; its community version would have to stop at every waypoint.

The path is a monotone piecewise cubic (PCHIP) through the waypoints: every waypoint
is reached exactly and no joint overshoots between two of them. The result is sampled
about every ``sample_s`` seconds, on whole interpolation ticks, into points whose
velocities are the path's; where MotoROS's cubic between two samples would still
exceed an acceleration limit, time is stretched until it does not.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any, Final, TypedDict

import numpy as np
import numpy.typing as npt

from pymotoros.errors import ConfigError
from pymotoros.models import ControllerModel, GroupModel, RobotModel
from pymotoros.models.rules import group_rules
from pymotoros.trajectory.files import Trajectory

F64Array = npt.NDArray[np.float64]

logger = logging.getLogger(__name__)


class WaypointPlanningError(ConfigError):
    """Waypoints that cannot be timed: outside the limits, too few, or bad scalings."""


DEFAULT_SAMPLE_S: Final = 0.05
"""Point spacing: 50 ms, a dozen MotoROS ticks per point, short enough that the cubic
between samples stays within 1 % of the path's acceleration."""
PLANNING_MARGIN: Final = 0.95
"""Fraction of each velocity/acceleration limit toppra plans with: the cubic MotoROS
fits between samples and whole-pulse rounding add a few per mille; 5 % keeps every
tick inside the limit."""
MIN_WAYPOINT_STEP: Final = 1e-6
"""rad (m): a joint that moves less than this from one waypoint to the next is held
still there; a tenth of a pulse on the finest axis we model (about 1e-5 rad per pulse)."""
_HALF_MS: Final = 0.5
_MAX_STRETCHES: Final = 8
"""Time stretches tried to bring the cubics within the limits (one or two suffice)."""
_GRIDPOINTS_PER_SEGMENT: Final = 50
"""toppra's discretisation per waypoint segment (its constraints hold at gridpoints)."""


class PlanTiming(TypedDict, total=False):
    """The timing keywords of :func:`plan_waypoints`, declared once so that a planner
    built on it (``trajectory/avoid.py``) passes them through without a copy."""

    velocity_scaling: float
    """0 < s ≤ 1: the share of each joint's maximum speed (default 1)."""
    acceleration_scaling: float
    """0 < s ≤ 1: the share of each joint's maximum acceleration (default 1)."""
    sample_s: float
    """Seconds between the trajectory's points (default :data:`DEFAULT_SAMPLE_S`)."""


def _monotone_path(ss: F64Array, way: F64Array) -> Any:
    """A C¹ path through the waypoints that never leaves the range of its neighbouring
    waypoints (PCHIP, per joint): a waypoint on a joint limit is never overshot, which
    toppra's cubic spline would do (toppra limits velocity and acceleration, not position)."""
    import toppra.interpolator
    from scipy.interpolate import PchipInterpolator

    spline = PchipInterpolator(ss, way, axis=0)
    derivatives = [spline, spline.derivative(1), spline.derivative(2)]

    class _Path(toppra.interpolator.AbstractGeometricPath):  # type: ignore[misc]
        def __call__(self, s: Any, order: int = 0) -> Any:
            return derivatives[order](s)

        @property
        def dof(self) -> int:
            return int(way.shape[1])

        @property
        def path_interval(self) -> F64Array:
            return np.array([ss[0], ss[-1]])

    return _Path()


def _cubic_accel(pos: F64Array, vel: F64Array, h: float) -> F64Array:
    """Largest |acceleration| per joint of the cubics MotoROS fits between samples h
    apart (§5: linear in time within a segment, so an end is the extreme)."""
    delta = np.diff(pos, axis=0)
    v0, v1 = vel[:-1], vel[1:]
    a_start = 6 * delta / h**2 - 2 * (v1 + 2 * v0) / h
    a_end = -6 * delta / h**2 + 2 * (2 * v1 + v0) / h
    return np.asarray(np.max(np.maximum(np.abs(a_start), np.abs(a_end)), axis=0))


def _limits(
    groups: Sequence[GroupModel], controller: ControllerModel
) -> tuple[F64Array, F64Array, F64Array, F64Array]:
    lower, upper, vmax, amax = [], [], [], []
    for group in groups:
        rules = group_rules(group, controller)
        for i, axis in enumerate(group.axes):
            lower.append(axis.lower)
            upper.append(axis.upper)
            # the tighter of the datasheet speed and what MotoROS's speed check allows
            vmax.append(min(axis.max_velocity, rules.max_speed[i]))
            amax.append(axis.max_acceleration)
    return np.array(lower), np.array(upper), np.array(vmax), np.array(amax)


def _checked_waypoints(
    waypoints: Sequence[Sequence[float]],
    names: tuple[str, ...],
    robot_name: str,
    lower: F64Array,
    upper: F64Array,
) -> F64Array:
    """The waypoints as an array, each row every joint, finite and within the limits."""
    lengths = {len(w) for w in waypoints}
    if lengths - {len(names)}:
        raise WaypointPlanningError(
            f"{robot_name} needs waypoints of {len(names)} joints, got rows of "
            f"{', '.join(str(n) for n in sorted(lengths))} values"
        )
    way = np.asarray(waypoints, dtype=np.float64)
    if way.ndim != 2 or way.shape[1] != len(names) or way.shape[0] < 2:
        raise WaypointPlanningError(
            f"{robot_name} needs at least 2 waypoints of {len(names)} joints, got shape {way.shape}"
        )
    if not np.all(np.isfinite(way)):
        w, j = (int(x) for x in np.argwhere(~np.isfinite(way))[0])
        raise WaypointPlanningError(
            f"waypoint {w}: {names[j]} = {way[w, j]} is not a finite number; give every "
            "joint in rad"
        )
    outside = (way < lower) | (way > upper)
    if outside.any():
        w, j = (int(x) for x in np.argwhere(outside)[0])
        raise WaypointPlanningError(
            f"waypoint {w}: {names[j]} = {way[w, j]:.6g} rad is outside its limits "
            f"[{lower[j]:.6g}, {upper[j]:.6g}]"
        )
    return way


def _merged(way: F64Array) -> F64Array:
    """Waypoints closer than MIN_WAYPOINT_STEP merged: the path parameter must increase."""
    kept = [way[0]]
    for w in way[1:]:
        # per joint: a step below MIN_WAYPOINT_STEP is no step (it would give the path
        # a needlessly steep, even overflowing, slope)
        w = np.where(np.abs(w - kept[-1]) <= MIN_WAYPOINT_STEP, kept[-1], w)
        if np.any(w != kept[-1]):
            kept.append(w)
    if len(kept) < 2:
        raise WaypointPlanningError("all waypoints are the same position: nothing to plan")
    return np.array(kept)


def _time_optimal(way: F64Array, v: F64Array, a: F64Array) -> Any:
    """toppra's time-optimal parameterisation of the monotone path through ``way``
    under the velocity and acceleration limits ``v``, ``a`` (at rest at both ends)."""
    import toppra
    import toppra.algorithm
    import toppra.constraint

    # path parameter: cumulative joint-space distance (well-conditioned spline)
    ss = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(way, axis=0), axis=1))))
    path = _monotone_path(ss, way)
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.column_stack((-v, v))),
        toppra.constraint.JointAccelerationConstraint(np.column_stack((-a, a))),
    ]
    grid = np.unique(
        np.concatenate(
            [np.linspace(ss[k], ss[k + 1], _GRIDPOINTS_PER_SEGMENT) for k in range(len(ss) - 1)]
        )
    )
    algo = toppra.algorithm.TOPPRA(
        constraints, path, gridpoints=grid, parametrizer="ParametrizeConstAccel"
    )
    timed = algo.compute_trajectory(0.0, 0.0)
    if timed is None:
        raise WaypointPlanningError("toppra found no feasible parameterisation (limits too tight?)")
    return timed


def _sampled(
    timed: Any, way: F64Array, a_limit: F64Array, period: int, sample_s: float
) -> tuple[F64Array, F64Array, F64Array]:
    """(times, positions, velocities) of whole-tick samples of ``timed``, stretched in
    time until MotoROS's cubics between them stay within ``a_limit``.

    Whole ticks per point: MotoROS executes one queue entry per tick, so a segment that
    is not a whole number of ticks leaves a short step the robot runs in a full tick (a
    velocity dip, and a slower motion than planned). Stretching time uniformly to whole
    ticks only lowers velocities and accelerations.
    """
    duration = float(timed.duration)
    count = max(1, math.ceil(duration / sample_s))
    seg_ms = max(period, math.ceil(duration * 1000.0 / count / period) * period)
    k = np.arange(count + 1, dtype=np.float64)
    pos = np.asarray(timed(k * duration / count), dtype=np.float64)
    path_vel = np.asarray(timed(k * duration / count, 1), dtype=np.float64)
    path_vel[0] = path_vel[-1] = 0.0
    pos[0], pos[-1] = way[0], way[-1]
    # MotoROS joins the samples with cubics, whose acceleration can exceed toppra's
    # where toppra's switches: stretch time (acceleration falls with its square) until
    # every cubic is within the scaled limits.
    for _ in range(_MAX_STRETCHES):
        vel = path_vel * ((duration / count) / (seg_ms / 1000.0))
        ratio = float(np.max(_cubic_accel(pos, vel, seg_ms / 1000.0) / a_limit))
        if ratio <= 1.0:
            break
        seg_ms = math.ceil(seg_ms * math.sqrt(ratio) / period) * period
    else:  # pragma: no cover - each stretch at least meets the ratio it measured
        raise WaypointPlanningError("could not bring the sampled cubics within the limits")
    # + half a ms: MotoROS truncates time × 1000 of the float32 time, which for a
    # decimal like 0.048 can land just below the intended whole ms.
    times = np.where(k == 0, 0.0, (k * seg_ms + _HALF_MS) / 1000.0)
    return times, pos, vel


def plan_waypoints(
    waypoints: Sequence[Sequence[float]],
    robot: RobotModel,
    controller: ControllerModel,
    *,
    velocity_scaling: float = 1.0,
    acceleration_scaling: float = 1.0,
    sample_s: float = DEFAULT_SAMPLE_S,
) -> Trajectory:
    """A trajectory through ``waypoints`` (rad, every joint of the robot, ROS order per
    group, groups in model order), starting and ending at rest.

    ``velocity_scaling`` and ``acceleration_scaling`` (0 < s ≤ 1) scale the model's
    limits as MoveIt's do. Raises :class:`WaypointPlanningError` for a waypoint that
    is not a finite number or is outside the joint limits, or scalings out of range.
    """
    for label, s in (("velocity", velocity_scaling), ("acceleration", acceleration_scaling)):
        if not (0.0 < s <= 1.0):
            raise WaypointPlanningError(f"{label} scaling must be in (0, 1], got {s}")
    if not (math.isfinite(sample_s) and sample_s > 0):
        raise WaypointPlanningError(
            f"the sample interval must be a positive number, got {sample_s}"
        )
    groups = robot.groups
    names = tuple(n for g in groups for n in g.joint_names)
    lower, upper, vmax, amax = _limits(groups, controller)
    way = _merged(_checked_waypoints(waypoints, names, robot.name, lower, upper))
    timed = _time_optimal(
        way,
        vmax * velocity_scaling * PLANNING_MARGIN,
        amax * acceleration_scaling * PLANNING_MARGIN,
    )
    times, pos, vel = _sampled(
        timed, way, amax * acceleration_scaling, controller.interpolation_period_ms, sample_s
    )
    pos = np.clip(pos, lower, upper)
    logger.info(
        "planned %d waypoints into %d points over %.3f s",
        len(way),
        len(times),
        float(times[-1]),
    )
    return Trajectory(names, times, pos, vel, robot=robot.name, controller=controller.type.value)
