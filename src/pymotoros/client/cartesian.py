"""Cartesian moves: a straight TCP line, time-parameterised within the joint limits.

MotoROS only takes joint trajectories, so a linear move is planned here: the line from
the current TCP pose to the goal (position along the segment, orientation along the
shortest rotation) is sampled densely and solved by inverse kinematics, each solution
seeded by the previous one so the arm stays on one branch. The path parameter s ∈ [0, 1]
is then timed by ruckig (jerk-limited, rest to rest) with limits derived from every
joint's velocity, acceleration and jerk limit along the path and from the TCP speed; the
trajectory points MotoROS receives are exact IK solutions on the line.

A move that cannot be made is refused before anything is sent, with the numbers:
an unreachable pose, a line through a singularity, a joint limit (which joint, by how
much, where on the line).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final, Literal

import numpy as np
import numpy.typing as npt

from pymotoros.client.planning import (
    DEFAULT_SAMPLE_PERIOD_S,
    MIN_SAMPLE_PERIOD_S,
    JointLimits,
    JointTrajectory,
    PlanningError,
    TrajectoryPoint,
    _check_scaling,
    _ruckig_plan,
    sample_count,
)
from pymotoros.client.tools import DEFAULT_TCP_SPEED_MM_S
from pymotoros.errors import KinematicsError
from pymotoros.kinematics import Chain, interpolate_pose, pose_to_matrix, rotation_angle

FloatArray = npt.NDArray[np.float64]
ReferenceFrame = Literal["base", "tool"]
"""What a relative move's offsets are measured in: the base axes or the tool's own."""

PATH_STEP_M: Final = 0.001
"""Spacing of the IK nodes along the line (1 mm): the joint-space derivatives used for
the timing are taken between these nodes."""
PATH_STEP_RAD: Final = math.radians(0.5)
"""Spacing of the nodes in orientation (0.5°) when the rotation dominates."""
MAX_NODES: Final = 20_000
"""Bound on the nodes of one move (20 m of line at 1 mm): a guard, not a practical limit."""
SINGULAR_JOINT_RATE: Final = 20.0
"""rad of joint motion per metre (or per rad) of TCP motion above which the line counts as
passing a singularity: 20 rad/m is 1.1° of joint per mm of TCP, far beyond any regular
pose of these arms."""
ACCEL_MARGIN: Final = 0.9
"""Share of each joint's acceleration and jerk limit the timing plans to (the curvature
term of the path is estimated between nodes, not exact)."""
TCP_SPEED_MARGIN: Final = 0.9
"""Share of the requested TCP speed the timing plans to: MotoROS's cubic between points
and the whole-pulse increments of each 4 ms tick add up to about 7 % on top of the plan
(measured by the property test in tests/client/test_cartesian.py: 202.5 mm/s per tick
for a 190 mm/s plan), so the requested speed stays a limit."""
_MM_PER_M: Final = 1000.0


def _percent(s: float) -> str:
    return f"{s * 100:.0f}% of the way"


def _explain_failure(chain: Chain, target: FloatArray, seed: FloatArray, s: float) -> str:
    """Why no joint values reach ``target``: a joint limit (which, by how much) or reach."""
    try:
        free = chain.ik(target, seed, "tcp", "base_link", limits=False)
    except KinematicsError:
        return f"the line leaves the robot's reach at {_percent(s)}"
    for name, q, lo, hi in zip(chain.joint_names, free.q, chain.lower, chain.upper, strict=True):
        if q > hi:
            return (
                f"{name} would reach {q:.4f} rad, {q - hi:.4f} rad ({math.degrees(q - hi):.2f}°) "
                f"beyond its upper limit {hi:.4f} at {_percent(s)}"
            )
        if q < lo:
            return (
                f"{name} would reach {q:.4f} rad, {lo - q:.4f} rad ({math.degrees(lo - q):.2f}°) "
                f"beyond its lower limit {lo:.4f} at {_percent(s)}"
            )
    return f"no joint values within the limits reach the line at {_percent(s)}"


def plan_linear_move(
    chain: Chain,
    start: Sequence[float],
    goal: FloatArray | Sequence[float],
    limits: JointLimits,
    *,
    tcp_speed_mm_s: float = DEFAULT_TCP_SPEED_MM_S,
    velocity_scaling: float = 1.0,
    acceleration_scaling: float = 1.0,
    sample_period: float = DEFAULT_SAMPLE_PERIOD_S,
) -> JointTrajectory:
    """A rest-to-rest trajectory moving ``chain``'s TCP in a straight line from its pose at
    joint values ``start`` to ``goal`` (6-tuple or 4×4 in base coordinates).

    The TCP never exceeds ``tcp_speed_mm_s``; every joint stays within its position,
    velocity (× ``velocity_scaling``), acceleration and jerk (× ``acceleration_scaling``)
    limits. Raises :class:`PlanningError` naming the problem and where on the line.
    """
    _check_scaling("velocity_scaling", velocity_scaling)
    _check_scaling("acceleration_scaling", acceleration_scaling)
    if not tcp_speed_mm_s > 0 or not math.isfinite(tcp_speed_mm_s):
        raise PlanningError(f"tcp_speed_mm_s must be a positive number, got {tcp_speed_mm_s}")
    if sample_period < MIN_SAMPLE_PERIOD_S:
        raise PlanningError(f"sample_period must be at least {MIN_SAMPLE_PERIOD_S} s")
    q0 = np.asarray(start, dtype=float)
    t_start = chain.fk(q0, "tcp", "base_link")
    goal_m = np.asarray(goal, dtype=float)
    if goal_m.shape != (4, 4):
        goal_m = pose_to_matrix([float(v) for v in goal_m.ravel()])
    goal_m = goal_m.copy()
    goal_m[2, 3] += chain.base_height  # base → base_link
    length = float(np.linalg.norm(goal_m[:3, 3] - t_start[:3, 3]))
    angle = rotation_angle(t_start, goal_m)
    n = len(q0)
    zeros = (0.0,) * n
    if length < 1e-9 and angle < 1e-9:
        return JointTrajectory((TrajectoryPoint(0.0, tuple(q0.tolist()), zeros, zeros),), 0.0)
    nodes = max(2, math.ceil(max(length / PATH_STEP_M, angle / PATH_STEP_RAD))) + 1
    if nodes > MAX_NODES:
        raise PlanningError(
            f"the line is {length:.3f} m long; at most {MAX_NODES * PATH_STEP_M:.0f} m per move"
        )

    # 1. IK along the line, each node seeded by the previous one (one branch).
    ss = np.linspace(0.0, 1.0, nodes)
    qs = np.empty((nodes, n))
    qs[0] = q0
    for i in range(1, nodes):
        target = interpolate_pose(t_start, goal_m, float(ss[i]))
        try:
            qs[i] = chain.ik(target, qs[i - 1], "tcp", "base_link", restarts=0).q
        except KinematicsError:
            raise PlanningError(
                "cannot move in a straight line: "
                + _explain_failure(chain, target, qs[i - 1], float(ss[i]))
            ) from None
    # 2. Joint rates along the path; a jump means a singularity (or a branch change).
    ds = 1.0 / (nodes - 1)
    d = np.diff(qs, axis=0) / ds  # dq/ds between nodes
    scale = max(length, angle)
    rate = np.abs(d).max(axis=1) / scale
    worst = int(np.argmax(rate))
    if rate[worst] > SINGULAR_JOINT_RATE:
        joint = chain.joint_names[int(np.argmax(np.abs(d[worst])))]
        pose = interpolate_pose(t_start, goal_m, float(ss[worst]))[:3, 3]
        raise PlanningError(
            f"cannot move in a straight line: it passes a singularity at "
            f"{_percent(float(ss[worst]))} (x {pose[0]:.3f}, y {pose[1]:.3f}, "
            f"z {pose[2] - chain.base_height:.3f} m): {joint} would turn "
            f"{rate[worst] / _MM_PER_M:.3f} rad per mm of TCP motion; "
            "move in joint space (move_joints) or choose another line"
        )
    # d²q/ds² between nodes (a two-node line has one segment and no curvature term)
    dd = np.diff(d, axis=0) / ds if len(d) > 1 else np.zeros((1, n))
    d_max = np.maximum(np.abs(d).max(axis=0), 1e-12)
    dd_max = np.abs(dd).max(axis=0)
    vmax = np.array(limits.max_velocity) * velocity_scaling
    amax = np.array(limits.max_acceleration) * acceleration_scaling * ACCEL_MARGIN
    jmax = np.array(limits.max_jerk) * acceleration_scaling * ACCEL_MARGIN
    # 3. Limits of the path parameter: ds/dt from the joint speeds and the TCP speed,
    # d²s/dt² from the joint accelerations minus the curvature term dd·(ds/dt)².
    v_s = float(np.min(vmax / d_max))
    if length > 0:
        v_s = min(v_s, TCP_SPEED_MARGIN * tcp_speed_mm_s / _MM_PER_M / length)
    for _ in range(60):  # halve the speed until the curvature leaves room to accelerate
        room = amax - dd_max * v_s**2
        if np.all(room > 0.1 * amax):
            break
        v_s /= 2
    a_s = float(np.min((amax - dd_max * v_s**2) / d_max))
    j_s = float(np.min(jmax / d_max))
    duration, _ = _ruckig_plan([0.0], [1.0], [v_s], [a_s], [j_s], 1)
    segments = sample_count(duration, sample_period)
    duration, samples = _ruckig_plan([0.0], [1.0], [v_s], [a_s], [j_s], segments)
    # 4. Points: exact IK on the line, velocities dq/ds · ds/dt.
    points = [TrajectoryPoint(0.0, tuple(q0.tolist()), zeros, zeros)]
    for k in range(1, segments):
        (s,), (sd,), (sdd,) = samples[k]
        s = min(max(s, 0.0), 1.0)
        i = min(int(s / ds), nodes - 2)
        frac = (s - ss[i]) / ds
        seed = qs[i] + frac * (qs[i + 1] - qs[i])
        q = chain.ik(interpolate_pose(t_start, goal_m, s), seed, "tcp", "base_link", restarts=0).q
        vel = np.clip(d[i] * sd, -vmax, vmax)
        acc = d[i] * sdd
        points.append(
            TrajectoryPoint(
                duration * k / segments, tuple(q.tolist()), tuple(vel.tolist()), tuple(acc.tolist())
            )
        )
    points.append(TrajectoryPoint(duration, tuple(qs[-1].tolist()), zeros, zeros))
    return JointTrajectory(tuple(points), duration)


def relative_target(
    current: FloatArray,
    delta: Sequence[float],
    frame: ReferenceFrame = "base",
) -> FloatArray:
    """The pose ``current`` (4×4) moved by ``delta`` = (dx, dy, dz, drx, dry, drz): in
    ``base`` the translation is along the base axes and the rotation about base axes
    through the TCP; in ``tool`` both are in the TCP's own frame."""
    if frame not in ("base", "tool"):
        raise PlanningError(f"frame must be 'base' or 'tool', not {frame!r}")
    step = pose_to_matrix([float(v) for v in delta])
    out = current.copy()
    if frame == "tool":
        return current @ step
    out[:3, 3] = current[:3, 3] + step[:3, 3]
    out[:3, :3] = step[:3, :3] @ current[:3, :3]
    return out
