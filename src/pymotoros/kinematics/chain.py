"""One control group's kinematic chain on Pinocchio: FK, Jacobian, IK nearest a seed.

Frames (docs/kinematics.md): ``base_link`` is the mounting surface, the root of the URDF;
``base`` is ``base_link`` raised by the group's ``base_height`` (the ROS-Industrial
``base`` frame, Yaskawa's robot coordinates). The chain ends at ``flange`` (the last
joint's frame), ``tool0`` (the URDF's tool mounting frame) and ``tcp`` (``tool0`` moved by
the active tool's offset). Poses are ``(x, y, z, rx, ry, rz)`` in metres and radians with
R = Rz·Ry·Rx: fixed-axis rotations about X, then Y, then Z, as Yaskawa gives Rx, Ry, Rz
and as URDF gives roll, pitch, yaw.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Final, Literal

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from pymotoros.errors import KinematicsError
from pymotoros.models.robots import AxisModel, GroupModel, JointGeometry, Transform, robot_model

FloatArray = npt.NDArray[np.float64]
FrameName = Literal["flange", "tool0", "tcp"]
Reference = Literal["base", "base_link"]

BASE: Final = "base"
BASE_LINK: Final = "base_link"

IK_POSITION_TOLERANCE_M: Final = 1e-10
"""IK stops when the position error is below this (far inside the 1e-6 m acceptance)."""
IK_ROTATION_TOLERANCE_RAD: Final = 1e-10
"""IK stops when the rotation error is below this."""
IK_ACCEPT_M: Final = 1e-8
"""A solution whose position error is below this is accepted (slow convergence near a
singularity may stop short of the stopping tolerance)."""
IK_ACCEPT_RAD: Final = 1e-8
"""A solution whose rotation error is below this is accepted."""
IK_MAX_ITERATIONS: Final = 200
"""Newton steps per start; a reachable pose near the start converges in well under 30."""
IK_DAMPING: Final = 1e-6
"""Levenberg–Marquardt damping (squared) of the least-squares step: keeps the step finite
near a singularity without slowing convergence away from one."""
IK_RESTARTS: Final = 24
"""Random starts tried after the seed itself fails (deterministic: a fixed RNG seed)."""
IK_MAX_STEP_RAD: Final = 0.5
"""Largest joint change of one Newton step: keeps the iteration on the seed's branch."""
SINGULARITY_SIGMA: Final = 1e-4
"""Smallest singular value of the 6×n Jacobian below which a pose counts as singular."""
_RNG_SEED: Final = 20261124
NO_TOOL: Final = Transform()
"""Tool 0 as after a boot: the TCP is tool0 itself."""


def joint_geometry(axis: AxisModel) -> JointGeometry:
    """The axis's origin and direction, or a clear error for a model without them."""
    if axis.geometry is None:
        raise KinematicsError(f"axis {axis.name} has no origin/axis data: no kinematic chain")
    return axis.geometry


def pose_to_matrix(pose: Sequence[float]) -> FloatArray:
    """4×4 homogeneous matrix of ``(x, y, z, rx, ry, rz)`` with R = Rz·Ry·Rx."""
    if len(pose) != 6:
        raise KinematicsError(f"a pose has 6 values (x, y, z, rx, ry, rz), got {len(pose)}")
    m = np.eye(4)
    m[:3, :3] = pin.rpy.rpyToMatrix(float(pose[3]), float(pose[4]), float(pose[5]))
    m[:3, 3] = [float(pose[0]), float(pose[1]), float(pose[2])]
    return m


def matrix_to_pose(m: FloatArray) -> tuple[float, float, float, float, float, float]:
    """``(x, y, z, rx, ry, rz)`` of a 4×4 matrix; rx, ry, rz in (−π, π], ry in [−π/2, π/2]."""
    rpy = pin.rpy.matrixToRpy(np.asarray(m[:3, :3], dtype=float))
    return (
        float(m[0, 3]),
        float(m[1, 3]),
        float(m[2, 3]),
        float(rpy[0]),
        float(rpy[1]),
        float(rpy[2]),
    )


def interpolate_pose(start: FloatArray, goal: FloatArray, s: float) -> FloatArray:
    """The 4×4 pose at ``s`` ∈ [0, 1] on the straight line from ``start`` to ``goal``:
    position linear, orientation along the shortest rotation (constant angular rate)."""
    m = np.eye(4)
    m[:3, 3] = start[:3, 3] + s * (goal[:3, 3] - start[:3, 3])
    rel = pin.log3(start[:3, :3].T @ goal[:3, :3])
    m[:3, :3] = start[:3, :3] @ pin.exp3(s * rel)
    return m


def rotation_angle(a: FloatArray, b: FloatArray) -> float:
    """The angle (rad) of the rotation from orientation ``a`` to ``b`` (4×4 or 3×3)."""
    return float(np.linalg.norm(pin.log3(a[:3, :3].T @ b[:3, :3])))


def _se3(frame: Transform) -> Any:
    return pin.SE3(pin.rpy.rpyToMatrix(*frame.rpy), np.array(frame.xyz, dtype=float))


@dataclass(frozen=True, slots=True)
class IkResult:
    """A solved IK: the joint values and the remaining position and rotation error."""

    q: FloatArray
    position_error_m: float
    rotation_error_rad: float


@dataclass(frozen=True, slots=True)
class _Built:
    """A group's Pinocchio model with one tool, and the ids of its named frames: read-only
    once built, so one copy serves every chain of that group and tool."""

    model: Any
    frame_ids: dict[str, int]


@lru_cache(maxsize=64)
def _built(group: GroupModel, tool: Transform) -> _Built:
    """Build the Pinocchio model of ``group`` with ``tool`` on tool0 (once per pair)."""
    model = pin.Model()
    model.name = group.name
    parent = 0
    mount = _se3(group.mount)
    for i, axis in enumerate(group.axes):
        geo = joint_geometry(axis)
        placement = _se3(geo.origin)
        if i == 0:
            placement = mount * placement
        direction = np.array(geo.axis, dtype=float)
        joint: Any = (
            pin.JointModelPrismaticUnaligned(direction)
            if axis.linear
            else pin.JointModelRevoluteUnaligned(direction)
        )
        parent = model.addJoint(
            parent,
            joint,
            placement,
            axis.name,
            np.array([1e3]),
            np.array([axis.max_velocity]),
            np.array([axis.lower]),
            np.array([axis.upper]),
        )
    last = parent
    tool0 = _se3(group.tool0) if group.tool0 is not None else pin.SE3.Identity()
    frames = {
        "flange": pin.SE3.Identity(),
        "tool0": tool0,
        "tcp": tool0 * _se3(tool),
    }
    ids = {
        name: model.addFrame(pin.Frame(name, last, 0, placement, pin.FrameType.OP_FRAME))
        for name, placement in frames.items()
    }
    return _Built(model, ids)


class Chain:
    """The kinematic chain of one control group with one tool mounted on ``tool0``.

    Each chain owns its workspace (Pinocchio data, the IK's random restarts): a user
    of kinematics (the controller, a client, the pendant) builds its own chains and
    never shares one. The model behind is built once per group and tool (read-only).
    """

    def __init__(self, group: GroupModel, tool: Transform = NO_TOOL) -> None:
        if any(a.geometry is None for a in group.axes):
            raise KinematicsError(
                f"group {group.name} has no joint geometry: give every axis an origin and axis"
            )
        self.group = group
        self.tool = tool
        self.joint_names = group.joint_names
        self.lower = np.array([a.lower for a in group.axes], dtype=float)
        self.upper = np.array([a.upper for a in group.axes], dtype=float)
        self.max_velocity = np.array([a.max_velocity for a in group.axes], dtype=float)
        self.base_height = group.base_height
        built = _built(group, tool)
        self.model = built.model
        self._frame_ids = built.frame_ids
        self._data = self.model.createData()
        self._rng = np.random.default_rng(_RNG_SEED)

    # --- conveniences ------------------------------------------------------------------

    @property
    def num_joints(self) -> int:
        """Number of joints the chain moves (the group's axes, in ROS order)."""
        return len(self.joint_names)

    def with_tool(self, tool: Transform) -> Chain:
        """The same chain with another tool on ``tool0`` (a new object; this one is unchanged)."""
        return Chain(self.group, tool)

    def _q(self, q: Sequence[float] | FloatArray) -> FloatArray:
        arr = np.asarray(q, dtype=float)
        if arr.shape != (self.num_joints,):
            raise KinematicsError(
                f"group {self.group.name} has {self.num_joints} joints, got {arr.shape[0]} values"
                if arr.ndim == 1
                else f"joint values must be a flat list of {self.num_joints} numbers"
            )
        return arr

    def _frame_id(self, frame: str) -> int:
        try:
            return self._frame_ids[frame]
        except KeyError:
            raise KinematicsError(
                f"unknown frame {frame!r}; frames: {', '.join(self._frame_ids)}"
            ) from None

    def _reference_z(self, reference: str) -> float:
        if reference == BASE:
            return self.base_height
        if reference == BASE_LINK:
            return 0.0
        raise KinematicsError(f"unknown reference frame {reference!r}; use 'base' or 'base_link'")

    # --- forward kinematics -------------------------------------------------------------

    def fk(
        self, q: Sequence[float] | FloatArray, frame: FrameName = "tcp", reference: Reference = BASE
    ) -> FloatArray:
        """4×4 pose of ``frame`` in ``reference`` at joint values ``q`` (ROS order)."""
        fid = self._frame_id(frame)
        dz = self._reference_z(reference)
        pin.framesForwardKinematics(self.model, self._data, self._q(q))
        m = np.array(self._data.oMf[fid].homogeneous, dtype=float)
        m[2, 3] -= dz
        return m

    def pose(
        self, q: Sequence[float] | FloatArray, frame: FrameName = "tcp", reference: Reference = BASE
    ) -> tuple[float, float, float, float, float, float]:
        """``(x, y, z, rx, ry, rz)`` of ``frame`` in ``reference`` (m, rad, R = Rz·Ry·Rx)."""
        return matrix_to_pose(self.fk(q, frame, reference))

    def position(self, q: Sequence[float] | FloatArray, frame: FrameName = "tcp") -> FloatArray:
        """Position of ``frame`` in ``base_link`` (m): the cheap call for speeds."""
        pin.framesForwardKinematics(self.model, self._data, self._q(q))
        return np.array(self._data.oMf[self._frame_id(frame)].translation, dtype=float)

    def jacobian(self, q: Sequence[float] | FloatArray, frame: FrameName = "tcp") -> FloatArray:
        """6×n Jacobian of ``frame``: rows vx, vy, vz, wx, wy, wz at the frame's origin, in
        the orientation of ``base_link`` (and of ``base``: the two differ by a translation)."""
        arr = self._q(q)
        pin.computeJointJacobians(self.model, self._data, arr)
        pin.updateFramePlacements(self.model, self._data)
        j = pin.getFrameJacobian(
            self.model, self._data, self._frame_id(frame), pin.LOCAL_WORLD_ALIGNED
        )
        # Pinocchio hands a one-joint Jacobian back as a flat vector.
        return np.reshape(np.array(j, dtype=float), (6, self.num_joints))

    def tcp_speed(
        self,
        q: Sequence[float] | FloatArray,
        dq: Sequence[float] | FloatArray,
        dt: float,
        frame: FrameName = "tcp",
    ) -> float:
        """Speed (m/s) of the TCP over one step of joint increments ``dq`` taking ``dt`` s:
        the straight distance between the two positions over the time. Two FK calls, no
        Jacobian: cheap enough to run every 4 ms tick (e.g. for an FSU TCP-speed limit)."""
        arr = self._q(q)
        p0 = self.position(arr, frame)
        p1 = self.position(arr + np.asarray(dq, dtype=float), frame)
        return float(np.linalg.norm(p1 - p0)) / dt

    def tcp_velocity(
        self,
        q: Sequence[float] | FloatArray,
        qd: Sequence[float] | FloatArray,
        frame: FrameName = "tcp",
    ) -> float:
        """Linear speed (m/s) of ``frame`` at joint values ``q`` and joint velocities ``qd``."""
        j = self.jacobian(q, frame)
        return float(np.linalg.norm(j[:3] @ np.asarray(qd, dtype=float)))

    # --- inverse kinematics -------------------------------------------------------------

    def _solve_from(
        self, start: FloatArray, target: Any, fid: int, limits: bool = True
    ) -> tuple[FloatArray, float, float]:
        model, data = self.model, self._data
        lower = self.lower if limits else np.full_like(self.lower, -np.inf)
        upper = self.upper if limits else np.full_like(self.upper, np.inf)
        q = np.clip(start, lower, upper)
        pos_err = rot_err = math.inf
        for _ in range(IK_MAX_ITERATIONS):
            pin.framesForwardKinematics(model, data, q)
            current = data.oMf[fid]
            e_pos = target.translation - current.translation
            e_rot = pin.log3(target.rotation @ current.rotation.T)
            pos_err = float(np.linalg.norm(e_pos))
            rot_err = float(np.linalg.norm(e_rot))
            if pos_err < IK_POSITION_TOLERANCE_M and rot_err < IK_ROTATION_TOLERANCE_RAD:
                break
            pin.computeJointJacobians(model, data, q)
            j = np.reshape(pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED), (6, -1))
            err = np.concatenate([e_pos, e_rot])
            step = j.T @ np.linalg.solve(j @ j.T + IK_DAMPING * np.eye(6), err)
            biggest = float(np.max(np.abs(step)))
            if biggest > IK_MAX_STEP_RAD:
                step *= IK_MAX_STEP_RAD / biggest
            q = np.clip(q + step, lower, upper)
        return q, pos_err, rot_err

    def _nearest_turn(self, q: FloatArray, seed: FloatArray) -> FloatArray:
        """Each revolute joint moved by whole turns towards the seed, inside its limits."""
        out = q.copy()
        for i, axis in enumerate(self.group.axes):
            if axis.linear:
                continue
            turns = round((seed[i] - q[i]) / (2 * math.pi))
            for k in (turns, turns - 1, turns + 1):
                cand = q[i] + 2 * math.pi * k
                if self.lower[i] <= cand <= self.upper[i] and abs(cand - seed[i]) < abs(
                    out[i] - seed[i]
                ):
                    out[i] = cand
        return out

    def ik(
        self,
        pose: Sequence[float] | FloatArray,
        seed: Sequence[float] | FloatArray,
        frame: FrameName = "tcp",
        reference: Reference = BASE,
        *,
        restarts: int = IK_RESTARTS,
        limits: bool = True,
    ) -> IkResult:
        """Joint values inside the limits that put ``frame`` at ``pose`` (a 6-tuple or a 4×4
        matrix in ``reference``), nearest ``seed``.

        The Newton iteration starts at the seed, so it finds the solution on the seed's
        branch (the nearest one for a seed near the pose); only if that fails are random
        starts tried, and of all the solutions they reach the one nearest the seed wins.
        Raises :class:`KinematicsError` saying how far the best attempt stayed from the pose.
        With ``limits=False`` the joint limits are ignored (to say which joint a pose
        would push past its limit, and by how much); no restarts are tried then.
        """
        target_m = np.asarray(pose, dtype=float)
        if target_m.shape != (4, 4):
            target_m = pose_to_matrix([float(v) for v in target_m.ravel()])
        target_m = target_m.copy()
        target_m[2, 3] += self._reference_z(reference)
        target = pin.SE3(target_m[:3, :3], target_m[:3, 3])
        fid = self._frame_id(frame)
        seed_q = self._q(seed)
        q, pe, re = self._solve_from(seed_q, target, fid, limits)
        if pe < IK_ACCEPT_M and re < IK_ACCEPT_RAD:
            q = self._nearest_turn(q, seed_q) if limits else q
            return IkResult(q, pe, re)
        if not limits:
            restarts = 0
        best: IkResult | None = None
        closest = (pe, re)
        for _ in range(restarts):
            start = self._rng.uniform(self.lower, self.upper)
            q, pe, re = self._solve_from(start, target, fid)
            if pe < IK_ACCEPT_M and re < IK_ACCEPT_RAD:
                q = self._nearest_turn(q, seed_q)
                if best is None or np.linalg.norm(q - seed_q) < np.linalg.norm(best.q - seed_q):
                    best = IkResult(q, pe, re)
            elif pe + re < closest[0] + closest[1]:
                closest = (pe, re)
        if best is not None:
            return best
        raise KinematicsError(
            f"group {self.group.name}: no joint values within the limits reach the pose "
            f"{tuple(round(v, 6) for v in matrix_to_pose(target_m))} ({reference} with z raised "
            f"to base_link): the best attempt stayed {closest[0] * 1000:.3f} mm and "
            f"{math.degrees(closest[1]):.3f}° away; check it is within reach and the limits"
        )

    # --- description for viewers --------------------------------------------------------

    def joint_frames(self, q: Sequence[float] | FloatArray) -> list[dict[str, Any]]:
        """Each joint's frame, then flange, tool0 and tcp, in ``base_link`` at ``q``: a
        JSON-able list of ``{"name", "xyz", "quat_xyzw", "axis"}`` for a 3D view."""
        pin.framesForwardKinematics(self.model, self._data, self._q(q))
        out: list[dict[str, Any]] = []
        for i, axis in enumerate(self.group.axes):
            m = self._data.oMi[i + 1]
            geo = joint_geometry(axis)
            out.append(_frame_json(axis.name, m, m.rotation @ np.array(geo.axis, dtype=float)))
        for name, fid in self._frame_ids.items():
            out.append(_frame_json(name, self._data.oMf[fid], None))
        return out


def _frame_json(name: str, m: Any, axis: FloatArray | None) -> dict[str, Any]:
    quat = pin.Quaternion(m.rotation)
    out: dict[str, Any] = {
        "name": name,
        "xyz": [float(v) for v in m.translation],
        "quat_xyzw": [float(quat.x), float(quat.y), float(quat.z), float(quat.w)],
    }
    if axis is not None:
        out["axis"] = [float(v) for v in axis]
    return out


def chain_for(group: GroupModel | str, tool: Transform = NO_TOOL, *, group_index: int = 0) -> Chain:
    """A new chain of a group (or of a robot model's ``group_index``-th group, by name),
    with ``tool`` on ``tool0``, and its own workspace: keep it rather than calling this
    per pose (the model behind is built once per group and tool)."""
    if isinstance(group, str):
        robot = robot_model(group)
        group = robot.groups[group_index]
    return Chain(group, tool)
