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

import contextlib
import math
from collections.abc import Sequence
from dataclasses import dataclass
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
    check_scaling,
    ruckig_plan,
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
NEAR_SINGULAR_SIGMA: Final = 0.05
"""Smallest singular value of the 6×n Jacobian (m and rad mixed, as Pinocchio gives it)
below which a failed line is explained as a singularity: regular poses of these arms
stay above 0.1; the wrist of an HC10 at joint_5_b = 6° is at 0.03."""
SINGULAR_PROBE_RAD: Final = 0.1
"""Joint step (5.7°) used to find which joint moves the arm out of a singularity."""
SINGULAR_GAIN: Final = 0.005
"""Rise of the smallest singular value over that step below which no single joint is
named (several lost directions at once, as at the HC10's all-zero pose)."""
READY_POSE: Final = (0.0, 0.0, 1.047, 0.0, -1.047, 0.0)
READY_HINT: Final = "[0, 0, 1.047, 0, -1.047, 0]"
"""A ready pose of the six-axis arms we model (joint_3 at 60°, joint_5 at -60°: the tool
points down, elbow and wrist bent, far from every singularity), named in the refusal."""
_MM_PER_M: Final = 1000.0


def _percent(s: float) -> str:
    return f"{s * 100:.0f}% of the way"


def _smallest_singular_value(chain: Chain, q: FloatArray) -> float:
    return float(np.linalg.svd(chain.jacobian(q), compute_uv=False)[-1])


@dataclass(frozen=True, slots=True)
class _Singularity:
    """How singular the arm is at some joint values, and which joints make it so."""

    lost: int
    """Directions the TCP cannot move in (singular values below NEAR_SINGULAR_SIGMA)."""
    sigma: float
    turning: str
    """The joints that turn without moving the TCP, as words."""
    key: str | None
    """The joint (with its value) whose move raises the smallest singular value most;
    None when no single joint gets the arm out."""


def _singularity(chain: Chain, q: FloatArray) -> _Singularity:
    _, sigma, vt = np.linalg.svd(chain.jacobian(q))
    lost = int(np.sum(sigma < NEAR_SINGULAR_SIGMA))
    names = chain.joint_names
    weights = np.abs(vt[len(sigma) - max(lost, 1) :]).max(axis=0)
    free = [names[i] for i in np.argsort(-weights) if weights[i] > 0.3] or list(names)
    turning = f"{', '.join(free[:-1])} and {free[-1]}" if len(free) > 1 else free[0]
    gains = []
    for i in range(len(q)):
        step = np.zeros(len(q))
        step[i] = SINGULAR_PROBE_RAD
        best = max(_smallest_singular_value(chain, q + s) for s in (step, -step))
        gains.append(best - sigma[-1])
    k = int(np.argmax(gains))
    key = None
    if gains[k] >= 0.5 * sigma[-1] + SINGULAR_GAIN:
        key = f"{names[k]} at {q[k]:.3f} rad ({math.degrees(q[k]):.1f}°)"
    return _Singularity(lost, float(sigma[-1]), turning, key)


def _ready_hint(q: FloatArray) -> str:
    return "a joint move to a ready pose first" + (
        f", e.g. move_joints({READY_HINT}) or `pymotoros move 0 0 60 0 -60 0 --deg`"
        if len(q) == len(READY_POSE)
        else ""
    )


def _explain_failure(chain: Chain, target: FloatArray, seed: FloatArray, s: float) -> str:
    """Why no joint values on the seed's branch reach ``target`` (``seed``: the last point
    solved): a singularity (which joints, what to do), a joint limit (which, by how much)
    or the edge of the robot's reach; each with what to do."""
    p = target[:3, 3]
    where = f"x {p[0]:.3f}, y {p[1]:.3f}, z {p[2] - chain.base_height:.3f} m"
    at = f"{_percent(s)} ({where})"
    joint_move = "make this a joint move (move_pose; --pose without --linear)"
    with contextlib.suppress(KinematicsError):  # on the seed's branch, limits ignored
        free = chain.ik(target, seed, "tcp", "base_link", limits=False).q
        for name, q, lo, hi in zip(chain.joint_names, free, chain.lower, chain.upper, strict=True):
            if q > hi or q < lo:
                side, limit, by = ("upper", hi, q - hi) if q > hi else ("lower", lo, lo - q)
                return (
                    f"{name} would reach {q:.4f} rad, {by:.4f} rad ({math.degrees(by):.2f}°) "
                    f"beyond its {side} limit {limit:.4f} rad at {_percent(s)}; choose another "
                    f"line or {joint_move}"
                )
    sing = _singularity(chain, seed)
    with_key = f", with {sing.key}" if sing.key is not None else ""
    try:  # from anywhere, within the limits: is the point reachable at all?
        chain.ik(target, seed, "tcp", "base_link")
    except KinematicsError as exc:
        gap = str(exc).rpartition("the best attempt stayed ")[2].partition(";")[0]
        head = f"the line leaves the robot's reach at {at}: the nearest the TCP gets stays {gap}"
        if sing.lost == 0:
            return f"{head}{with_key}; choose a target nearer the robot, or {joint_move}"
        return (
            f"{head}: the arm stands at a singularity ({sing.turning} turn without moving "
            f"the TCP{with_key}). Make {_ready_hint(seed)}, or {joint_move}"
        )
    if sing.lost == 0:
        return f"the arm would have to change its configuration at {at}; {joint_move}"
    head = (
        f"the arm is at a singularity at {at}: it cannot move the TCP in {sing.lost} of "
        f"6 directions there ({sing.turning} turn without moving it; smallest singular "
        f"value of the Jacobian {sing.sigma:.4f})"
    )
    if sing.key is None:  # no single joint gets it out
        return f"{head}. Make {_ready_hint(seed)}, or {joint_move}"
    name = sing.key.split(" ")[0]
    return f"{head}{with_key}. Move {name} away ({_ready_hint(seed)}), or {joint_move}"


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
    check_scaling("velocity_scaling", velocity_scaling)
    check_scaling("acceleration_scaling", acceleration_scaling)
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
    duration, _ = ruckig_plan([0.0], [1.0], [v_s], [a_s], [j_s], 1)
    segments = sample_count(duration, sample_period)
    duration, samples = ruckig_plan([0.0], [1.0], [v_s], [a_s], [j_s], segments)
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
