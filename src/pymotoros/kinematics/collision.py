"""Collision checks of the robot against the cell's obstacles and itself, on Coal.

Both the twin (a contact stops the robot, ``controller/safety/contact.py``) and the
offline check and planner (``trajectory/``) need the same answer to "does the robot
touch something at these joints?", and both may import ``kinematics`` but not each
other, so the checker lives here beside the chains it places.

Each robot group's links are capsules (radii: the group's ``link_radii``, declared
with its joints in :mod:`pymotoros.models.robots`) placed by the group's own Pinocchio
model (its own data: nothing shared with another user of the kinematics); the active
tool is its tool file's ``shape`` on the flange, or a capsule from ``tool0`` to its TCP
(:meth:`GroupBody.set_tool`). The obstacles come from :mod:`pymotoros.models.workspace`.
Coal (FCL's successor, a dependency of Pinocchio) computes the exact signed distances.

Cost: the narrow phase runs only on pairs whose bounding spheres are within
:data:`NEAR_M`: a probe far from every obstacle is one forward kinematics, one
placement per link and one numpy distance matrix. The twin goes further and probes
only when the robot may have moved as far as its last clearance (see
:meth:`CollisionWorld.joint_reach`).

Self-collision: pairs of links of one group that are not neighbours in the chain and
do not already touch (within :data:`SELF_NEIGHBOUR_M`) at the zero pose (the rule
MoveIt's setup assistant applies to build its "disabled collisions" list: such pairs
touch by construction of the simple shapes, not because the arm is folded onto itself).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import coal
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from pymotoros.kinematics.chain import Chain
from pymotoros.models.cell import CellModels
from pymotoros.models.cell_tools import CellTool
from pymotoros.models.robots import GroupKind, GroupModel, Transform
from pymotoros.models.workspace import (
    DEFAULT_TOOL_RADIUS_M,
    Box,
    Capsule,
    Cylinder,
    Obstacle,
    Shape,
    ToolShape,
    Workspace,
)

FloatArray = npt.NDArray[np.float64]

NEAR_M: Final = 0.05
"""Pairs whose bounding spheres are closer than this get Coal's exact distance: the
clearance a probe returns is then exact near the robot, so the twin's next probe is
not due for at least this much travel."""
TOUCH_M: Final = 0.0
"""A signed distance at or below this is a contact (the shapes touch or overlap)."""
SELF_NEIGHBOUR_M: Final = 0.005
"""Two links closer than this at the zero pose count as neighbours for self-collision:
their capsules meet at a shared joint (the MH5's T link sits 80 mm past B, exactly its
two radii), not because the arm is folded onto itself."""
_MIN_SEGMENT_M: Final = 1e-9
TOOL_LINK: Final = "tool"
"""The link name of the tool's shape in a contact (``R1 tool touches obstacle 'table'``)."""


def link_name(joint_name: str) -> str:
    """The ROS-Industrial link after a joint: ``joint_1_s`` → ``link_1_s``,
    ``arm_left_joint_2_l`` → ``arm_left_link_2_l``."""
    return joint_name.replace("joint", "link", 1) if "joint" in joint_name else f"{joint_name}_link"


@dataclass(frozen=True, slots=True)
class Contact:
    """A robot link touching an obstacle (or, for a self-collision, another link)."""

    obstacle: str
    """The obstacle's name; for a self-collision the other link's name."""
    link: str
    group: str
    distance_m: float
    """Signed distance (≤ 0: the depth of the overlap)."""
    self_collision: bool = False

    def as_dict(self) -> dict[str, object]:
        return {
            "obstacle": self.obstacle,
            "link": self.link,
            "group": self.group,
            "depth_mm": round(-self.distance_m * 1000.0, 3),
            "self_collision": self.self_collision,
        }


def _se3(frame: Transform) -> Any:
    return pin.SE3(pin.rpy.rpyToMatrix(*frame.rpy), np.array(frame.xyz, dtype=float))


def _geometry(shape: Shape) -> Any:
    if isinstance(shape, Box):
        return coal.Box(*shape.size)
    if isinstance(shape, Cylinder):
        return coal.Cylinder(shape.radius, shape.length)
    return coal.Sphere(shape.radius)


def _half_extents(shape: Shape) -> tuple[float, float, float]:
    """Half sizes of the shape's bounding box in its own axes."""
    if isinstance(shape, Box):
        return (shape.size[0] / 2, shape.size[1] / 2, shape.size[2] / 2)
    if isinstance(shape, Cylinder):
        return (shape.radius, shape.radius, shape.length / 2)
    return (shape.radius, shape.radius, shape.radius)


def _segment(a: FloatArray, b: FloatArray, radius: float) -> tuple[Any, Any, float]:
    """A capsule of ``radius`` around segment a→b: (Coal shape, placement, bounding radius)."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    if length < _MIN_SEGMENT_M:
        return coal.Sphere(radius), pin.SE3(np.eye(3), a.copy()), radius
    rot = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), axis / length).matrix()
    return coal.Capsule(radius, length), pin.SE3(rot, (a + b) / 2.0), length / 2.0 + radius


@dataclass(slots=True)
class _Part:
    """One shape on one link: the link's joint (0: the base), its name and placement."""

    joint: int
    order: int
    """Position along the chain (base 0, link i → i, tool n+1): neighbours differ by 1."""
    name: str
    geometry: Any
    local: Any
    bound: float
    world: Any = None
    """The placement in the workspace frame at the latest place (computed when asked:
    :meth:`GroupBody.world_of`)."""
    center: Any = None
    """The world position of the part's centre at the latest place."""
    radius: float = 0.0
    half: float = 0.0
    """Half the capsule's segment (0 for a sphere)."""
    local_ends: Any = None
    """The segment's two end points in the joint's frame, homogeneous (2 × 4)."""

    def __post_init__(self) -> None:
        # a box (a tool's shape) has no radius: its bounding sphere stands in for the
        # lever arms and the reach, which only need an upper bound
        self.radius = float(getattr(self.geometry, "radius", self.bound))
        self.half = float(getattr(self.geometry, "halfLength", 0.0))
        center = np.asarray(self.local.translation, dtype=float)
        along = np.asarray(self.local.rotation, dtype=float)[:, 2] * self.half
        self.local_ends = np.array([[*(center + along), 1.0], [*(center - along), 1.0]])


class GroupBody:
    """One robot group's links as capsules, placed by its own Pinocchio model."""

    def __init__(
        self,
        group: GroupModel,
        base: Transform | None = None,
        *,
        tool_radius: float = DEFAULT_TOOL_RADIUS_M,
    ) -> None:
        radii = group.link_radii
        if not radii:  # a base or station axis: the robot model refuses a robot group without
            raise ValueError(f"group {group.name} has no collision shapes (no link_radii)")
        chain = Chain(group)
        self.name = group.name
        self.model = chain.model
        self.data = self.model.createData()
        base = base if base is not None else Transform()
        self.base = _se3(base)
        self._identity_base = base == Transform()
        self.num_joints = n = group.num_axes
        self._tool_radius = tool_radius
        placements = self.model.jointPlacements
        parts: list[_Part] = []
        zero = np.zeros(3)
        mount = np.array(group.mount.xyz, dtype=float)
        first = np.array(placements[1].translation, dtype=float)
        if float(np.linalg.norm(mount)) > _MIN_SEGMENT_M:  # a column up to the mount (torso)
            parts.append(_Part(0, 0, "base_link", *_segment(zero, mount, radii[0])))
            parts.append(_Part(0, 0, "base_link", *_segment(mount, first, radii[0])))
        else:
            parts.append(_Part(0, 0, "base_link", *_segment(zero, first, radii[0])))
        tool0 = _se3(group.tool0) if group.tool0 is not None else pin.SE3.Identity()
        self._tool0 = tool0
        self.lengths: list[float] = []
        """Per joint, the length of its link's segment (for the reach bound)."""
        for i in range(1, n + 1):
            end = (
                np.array(placements[i + 1].translation, dtype=float)
                if i < n
                else np.array(tool0.translation, dtype=float)
            )
            name = link_name(group.axes[i - 1].name)
            parts.append(_Part(i, i, name, *_segment(zero, end, radii[i])))
            self.lengths.append(float(np.linalg.norm(end)))
        self.parts = parts
        self.base_round = self._base_round(group)
        """The base link's shapes lie on the first joint's axis (rotating about it changes
        no distance to them)."""
        self.frames: list[Any] = [pin.SE3.Identity() for _ in range(n)]
        """Per joint, its frame in the workspace frame at the latest :meth:`place`."""
        self._homogeneous = np.tile(np.eye(4), (n + 1, 1, 1))
        """Per joint (0: the base link), its frame as a 4 × 4 matrix at the latest place."""
        self._homogeneous[0] = np.asarray(self.base.homogeneous, dtype=float)
        self._stack_parts: list[_Part] = []
        self._part_joints = np.zeros(0, dtype=int)
        self._local_ends = np.zeros((0, 2, 4))
        self.ends = np.zeros((0, 2, 3))
        """Every part's segment end points in the workspace frame at the latest place."""
        self._joint_axes = np.array(
            [a.geometry.axis if a.geometry is not None else (0.0, 0.0, 1.0) for a in group.axes],
            dtype=float,
        )
        self._linear = np.array([a.linear for a in group.axes])
        self._tool_key: tuple[Transform, ToolShape | None] | None = None
        self._tool_given: Transform | CellTool | None = None
        self.tool_part: _Part | None = None
        self.pairs = self._self_pairs()

    def _base_round(self, group: GroupModel) -> bool:
        first = self.model.jointPlacements[1]
        axis = np.array(first.rotation, dtype=float) @ np.array(
            group.axes[0].geometry.axis if group.axes[0].geometry else (0.0, 0.0, 1.0)
        )
        origin = np.array(first.translation, dtype=float)
        for part in self.parts:
            if part.joint:
                continue
            center = np.array(part.local.translation, dtype=float)
            direction = np.array(part.local.rotation, dtype=float)[:, 2]
            off = center - origin
            if float(np.linalg.norm(off - np.dot(off, axis) * axis)) > _MIN_SEGMENT_M:
                return False
            if float(np.linalg.norm(np.cross(direction, axis))) > _MIN_SEGMENT_M:
                return False
        return True

    # --- the tool -------------------------------------------------------------------

    def set_tool(self, tool: Transform | CellTool) -> None:
        """Mount a tool on ``tool0``: its TCP (a bare :class:`Transform`) or its tool file
        (TCP and shape). Cached: the same tool again is no work."""
        if tool is self._tool_given:  # the twin asks with the same object each check
            return
        self._tool_given = tool
        data = tool if isinstance(tool, CellTool) else CellTool(0, tcp=tool)
        key = (data.tcp, data.shape)
        if key == self._tool_key:
            return
        self._tool_key = key
        self.tool_part = self._tool_part(data)
        self.pairs = self._self_pairs()

    def _tool_part(self, tool: CellTool) -> _Part | None:
        """The tool's shape on the last link: the one place it is built, for the twin's
        contact check, ``check`` and ``plan --avoid`` alike. With a ``shape`` in its tool
        file, that shape at its pose on tool0; else a capsule from tool0 to the TCP of
        radius ``workspace.tool_radius_m`` (none for a TCP on tool0)."""
        n = self.num_joints
        if tool.shape is not None:
            local = self._tool0 * _se3(tool.shape.pose)
            shape = tool.shape.shape
            geometry = (
                coal.Capsule(shape.radius, shape.length)
                if isinstance(shape, Capsule)
                else _geometry(shape)
            )
            return _Part(n, n + 1, TOOL_LINK, geometry, local, shape.bounding_radius)
        tcp = self._tool0 * _se3(tool.tcp)
        a = np.array(self._tool0.translation, dtype=float)
        b = np.array(tcp.translation, dtype=float)
        if float(np.linalg.norm(b - a)) < _MIN_SEGMENT_M:
            return None
        return _Part(n, n + 1, TOOL_LINK, *_segment(a, b, self._tool_radius))

    @property
    def all_parts(self) -> list[_Part]:
        return self.parts if self.tool_part is None else [*self.parts, self.tool_part]

    # --- placement ------------------------------------------------------------------

    def place(self, q: Sequence[float] | FloatArray) -> list[_Part]:
        """Every part's position at joints ``q`` (ROS order); returns the parts.

        One placement is read per joint (Pinocchio's per-call cost dominates here); the
        parts' end points and centres follow in one numpy product.
        """
        pin.forwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        omi = self.data.oMi
        base = None if self._identity_base else self.base
        frames = self.frames
        stack = self._homogeneous
        for j in range(1, self.num_joints + 1):
            frame = omi[j] if base is None else base * omi[j]
            frames[j - 1] = frame
            stack[j] = frame.homogeneous
        parts = self.all_parts
        if self._stack_parts is not parts:
            self._restack(parts)
        ends = np.einsum("pij,pej->pei", stack[self._part_joints], self._local_ends)[:, :, :3]
        self.ends = ends
        centers = ends.mean(axis=1)
        for part, center in zip(parts, centers, strict=True):
            part.center = center
            part.world = None
        return parts

    def _restack(self, parts: list[_Part]) -> None:
        self._stack_parts = parts
        self._part_joints = np.array([p.joint for p in parts])
        self._local_ends = np.array([p.local_ends for p in parts], dtype=float)

    def world_of(self, part: _Part) -> Any:
        """The part's placement (SE3) at the latest :meth:`place` (for Coal)."""
        if part.world is None:
            m = self.frames[part.joint - 1] * part.local if part.joint else part.local
            if part.joint == 0 and not self._identity_base:
                m = self.base * m
            part.world = m
        return part.world

    def lever_arms(self) -> list[float]:
        """Per joint, the farthest any point of the links it moves lies from its axis, at
        the latest :meth:`place`: how far (m) they move per radian of that joint now.
        While the arm moves by ``d`` metres these grow by at most ``d``."""
        return [float(x) for x in self.part_levers(self.all_parts).max(axis=0)]

    def part_levers(self, parts: Sequence[_Part]) -> FloatArray:
        """(parts × joints): the farthest point of each part from each joint's axis that
        moves it (0 for a joint after the part), at the latest :meth:`place`."""
        n = self.num_joints
        stack = self._homogeneous[1:]
        axes = np.einsum("nij,nj->ni", stack[:, :3, :3], self._joint_axes)
        origins = stack[:, :3, 3]
        index = {id(p): i for i, p in enumerate(self._stack_parts)}
        ends = self.ends[[index[id(p)] for p in parts]]  # (P, 2, 3)
        diff = ends[:, :, None, :] - origins[None, None, :, :]  # (P, 2, n, 3)
        axial = np.einsum("pend,nd->pen", diff, axes)
        square = np.einsum("pend,pend->pen", diff, diff) - axial * axial
        levers = np.sqrt(np.maximum(square, 0.0)).max(axis=1)  # (P, n)
        levers += np.array([p.radius for p in parts], dtype=float)[:, None]
        levers[:, self._linear] = 1.0  # a linear axis moves every point 1 m per metre
        joints = np.array([p.joint for p in parts])
        moved = joints[:, None] >= np.arange(1, n + 1)[None, :]
        return np.where(moved, levers, 0.0)

    def reach(self) -> list[float]:
        """Per joint, an upper bound of the distance from its axis to any point of the
        links it moves (the chain's length beyond it, the tool, the thickest capsule)."""
        part = self.tool_part
        tool = (
            float(np.linalg.norm(np.asarray(part.local.translation))) + part.bound
            if part is not None
            else 0.0
        )
        thickest = max(p.bound for p in self.all_parts)
        return [sum(self.lengths[k:]) + tool + thickest for k in range(self.num_joints)]

    def _self_pairs(self) -> list[tuple[int, int]]:
        """Part index pairs checked for self-collision (see the module docstring)."""
        parts = self.place(np.zeros(self.num_joints))
        out = []
        for i, a in enumerate(parts):
            for j in range(i + 1, len(parts)):
                b = parts[j]
                if abs(a.order - b.order) < 2:
                    continue
                d = _distance(a.geometry, self.world_of(a), b.geometry, self.world_of(b))
                if d > SELF_NEIGHBOUR_M:
                    out.append((i, j))
        return out


def _distance(g1: Any, m1: Any, g2: Any, m2: Any) -> float:
    result = coal.DistanceResult()
    return float(
        coal.distance(g1, coal.Transform3s(m1), g2, coal.Transform3s(m2), _DISTANCE, result)
    )


_DISTANCE: Final = coal.DistanceRequest()


@dataclass(frozen=True, slots=True)
class _PlacedObstacle:
    obstacle: Obstacle
    geometry: Any
    transform: Any
    center: tuple[float, float, float]


class CollisionWorld:
    """The robot groups of a cell and its obstacles: contacts and clearance at joints."""

    def __init__(
        self,
        groups: Sequence[GroupModel],
        workspace: Workspace,
    ) -> None:
        self.workspace = workspace
        self.groups = tuple(groups)
        self.bodies: list[GroupBody | None] = []
        for group in groups:
            if group.kind is not GroupKind.ROBOT:  # base and station axes have no shapes
                self.bodies.append(None)
                continue
            self.bodies.append(
                GroupBody(
                    group,
                    workspace.base(group.name),
                    tool_radius=workspace.tool_radius_m,
                )
            )
        self.set_obstacles(workspace)

    def set_obstacles(self, workspace: Workspace) -> None:
        """Place the workspace's obstacles (at boot, and when one is added or moved)."""
        self.workspace = workspace
        placed = []
        rotations = []
        halves = []
        for obstacle in workspace.obstacles:
            m = _se3(obstacle.pose)
            if obstacle.frame:
                m = _se3(workspace.base(obstacle.frame)) * m
            t = m.translation
            placed.append(
                _PlacedObstacle(
                    obstacle,
                    _geometry(obstacle.shape),
                    coal.Transform3s(m),
                    (float(t[0]), float(t[1]), float(t[2])),
                )
            )
            rotations.append(np.array(m.rotation, dtype=float))
            halves.append(_half_extents(obstacle.shape))
        self._obstacles = placed
        self._last_placed: list[tuple[GroupBody, _Part]] = []
        self._last_clearances = np.zeros(0)
        self._last_gaps = np.zeros((0, 0))
        self._centers = np.array([p.center for p in placed], dtype=float).reshape(-1, 3)
        self._rotations = np.array(rotations, dtype=float).reshape(-1, 3, 3)
        self._halves = np.array(halves, dtype=float).reshape(-1, 3)

    @property
    def has_obstacles(self) -> bool:
        return bool(self._obstacles)

    def set_tool(self, group_index: int, tool: Transform | CellTool) -> None:
        """The active tool of a group: its tool file (TCP and shape), or its TCP alone
        (a capsule from tool0), see :meth:`GroupBody.set_tool`."""
        body = self.bodies[group_index]
        if body is not None:
            body.set_tool(tool)

    def lever_arms(self, group_index: int) -> list[float]:
        """:meth:`GroupBody.lever_arms` of a group at its latest probe ([] without shapes)."""
        body = self.bodies[group_index]
        return body.lever_arms() if body is not None else []

    def self_invariant_joints(self, group_index: int) -> tuple[int, ...]:
        """Joints (ROS index) whose motion changes no self-collision distance of a group:
        the first joint when the base link is round about its axis (every single arm we
        model: turning S turns the whole arm over a base that looks the same)."""
        body = self.bodies[group_index]
        return (0,) if body is not None and body.base_round else ()

    def joint_reach(self, group_index: int) -> list[float]:
        """Per joint of a group, how far (m) a point of the robot moves per radian at most
        (0 for a group without shapes): Σ |Δq| × reach bounds any point's travel."""
        body = self.bodies[group_index]
        return body.reach() if body is not None else []

    # --- queries --------------------------------------------------------------------

    def _place(self, qs: Sequence[Sequence[float] | FloatArray]) -> list[tuple[GroupBody, _Part]]:
        """The moving parts, placed: the base link is bolted to whatever it stands on,
        which is therefore no contact (it still counts for self-collision)."""
        placed: list[tuple[GroupBody, _Part]] = []
        for body, q in zip(self.bodies, qs, strict=False):
            if body is not None:
                placed.extend((body, part) for part in body.place(q) if part.joint)
        return placed

    def probe(self, qs: Sequence[Sequence[float] | FloatArray]) -> tuple[float, list[Contact]]:
        """(clearance, contacts) of the robot at joints ``qs`` (per group, ROS order)
        against the obstacles: the clearance is a lower bound of the smallest distance
        (exact within :data:`NEAR_M`), ``inf`` without obstacles."""
        if not self._obstacles:
            return math.inf, []
        placed = self._place(qs)
        if not placed:
            return math.inf, []
        centers = np.array([p.center for _, p in placed], dtype=float)
        bounds = np.array([p.bound for _, p in placed], dtype=float)
        # broad phase: each part's bounding sphere against each obstacle's bounding box,
        # in the box's own axes (a lower bound of the true distance)
        local = np.einsum("nji,pnj->pni", self._rotations, centers[:, None, :] - self._centers)
        outside = np.maximum(np.abs(local) - self._halves, 0.0)
        gaps = np.sqrt((outside * outside).sum(axis=2)) - bounds[:, None]
        contacts: list[Contact] = []
        for i, j in np.argwhere(gaps <= NEAR_M):
            body, part = placed[int(i)]
            obst = self._obstacles[int(j)]
            result = coal.DistanceResult()
            d = float(
                coal.distance(
                    part.geometry,
                    coal.Transform3s(body.world_of(part)),
                    obst.geometry,
                    obst.transform,
                    _DISTANCE,
                    result,
                )
            )
            gaps[i, j] = d
            if d <= TOUCH_M:
                contacts.append(Contact(obst.obstacle.name, part.name, body.name, d))
        self._last_placed = placed
        self._last_clearances = gaps.min(axis=1)
        self._last_gaps = gaps
        return float(self._last_clearances.min()), contacts

    def nearest(self, qs: Sequence[Sequence[float] | FloatArray]) -> Contact | None:
        """The link and obstacle nearest each other at ``qs``, with their signed distance
        (exact within :data:`NEAR_M`); None without obstacles or moving parts."""
        if not math.isfinite(self.probe(qs)[0]):
            return None
        i, j = np.unravel_index(int(np.argmin(self._last_gaps)), self._last_gaps.shape)
        body, part = self._last_placed[int(i)]
        name = self._obstacles[int(j)].obstacle.name
        return Contact(name, part.name, body.name, float(self._last_gaps[i, j]))

    def part_budgets(self) -> list[tuple[int, FloatArray, FloatArray]]:
        """After :meth:`probe`, per group with shapes: (group index, each moving part's
        clearance c (m), its levers (parts × joints): how far it moves per radian of each
        joint now). Levers grow by at most the distance moved, so a part cannot touch
        anything while Σ_k |Δq_k| × (lever_k + c) stays below its c: finer than one
        clearance and one lever for the whole arm, because the part nearest an obstacle
        (a forearm above the table) is seldom the one that moves most."""
        out = []
        for g, body in enumerate(self.bodies):
            if body is None:
                continue
            rows = [i for i, (b, _) in enumerate(self._last_placed) if b is body]
            parts = [self._last_placed[i][1] for i in rows]
            clear = self._last_clearances[rows]
            out.append((g, clear, body.part_levers(parts)))
        return out

    def contacts(self, qs: Sequence[Sequence[float] | FloatArray]) -> list[Contact]:
        """Every link touching an obstacle at joints ``qs``."""
        return self.probe(qs)[1]

    def self_distances(self, qs: Sequence[Sequence[float] | FloatArray]) -> list[Contact]:
        """The distance of every pair checked for self-collision at ``qs`` (one
        :class:`Contact` each, touching or not): exact within :data:`NEAR_M`, else the
        lower bound of their bounding spheres."""
        out: list[Contact] = []
        for body, q in zip(self.bodies, qs, strict=False):
            if body is None:
                continue
            parts = body.place(q)
            centers = [p.center for p in parts]
            transforms: dict[int, Any] = {}
            for i, j in body.pairs:
                a, b = parts[i], parts[j]
                gap = float(np.linalg.norm(centers[i] - centers[j])) - a.bound - b.bound
                if gap > NEAR_M:
                    out.append(Contact(a.name, b.name, body.name, gap, self_collision=True))
                    continue
                for k in (i, j):
                    if k not in transforms:
                        transforms[k] = coal.Transform3s(body.world_of(parts[k]))
                d = float(
                    coal.distance(
                        a.geometry,
                        transforms[i],
                        b.geometry,
                        transforms[j],
                        _DISTANCE,
                        coal.DistanceResult(),
                    )
                )
                out.append(Contact(a.name, b.name, body.name, d, self_collision=True))
        return out

    def self_contacts(self, qs: Sequence[Sequence[float] | FloatArray]) -> list[Contact]:
        """Every pair of non-neighbouring links of one group that touch at ``qs``."""
        return [c for c in self.self_distances(qs) if c.distance_m <= TOUCH_M]

    def all_contacts(self, qs: Sequence[Sequence[float] | FloatArray]) -> list[Contact]:
        """Obstacle contacts and self-collisions at ``qs``."""
        return [*self.contacts(qs), *self.self_contacts(qs)]

    # --- paths ----------------------------------------------------------------------

    @property
    def joint_counts(self) -> tuple[int, ...]:
        """Joints per group, in the order a joint vector of every group holds them."""
        return tuple(g.num_axes for g in self.groups)

    def free_waypoints(
        self,
        waypoints: Sequence[Sequence[float]],
        *,
        time_limit_s: float | None = None,
        lower: Sequence[float] | None = None,
        upper: Sequence[float] | None = None,
        labels: Sequence[str] = (),
    ) -> list[list[float]]:
        """Collision-free joint waypoints through ``waypoints`` (every joint of every
        group), searched by OMPL within the joint limits (or ``lower`` … ``upper``):
        :func:`pymotoros.kinematics.path_search.free_waypoints`."""
        from pymotoros.kinematics import path_search  # OMPL loads only when planning

        axes = [a for g in self.groups for a in g.axes]
        return path_search.free_waypoints(
            self,
            waypoints,
            self.joint_counts,
            [a.lower for a in axes] if lower is None else lower,
            [a.upper for a in axes] if upper is None else upper,
            time_limit_s=path_search.DEFAULT_TIME_LIMIT_S if time_limit_s is None else time_limit_s,
            labels=labels,
        )

    def segment_contacts(self, a: Sequence[float], b: Sequence[float]) -> list[Contact]:
        """The first contact anywhere on the straight joint path a → b (every joint of
        every group), [] when free: :func:`pymotoros.kinematics.path_search.segment_contacts`."""
        from pymotoros.kinematics import path_search

        return [
            c
            for c in path_search.segment_contacts(self, a, b, self.joint_counts)
            if isinstance(c, Contact)
        ]


def world_for_cell(cell: CellModels, tools: Sequence[int | None] = ()) -> CollisionWorld:
    """The collision world of a cell file as the client reads it (its groups in cell
    order, its ``[workspace]``), each group with a tool on its flange: ``tools[g]`` (a
    tool number; missing or None: the cell's default, ``[initial.tool]`` or tool 0, as
    the twin boots), its shape from the cell's tool data (:meth:`GroupBody.set_tool`)."""
    world = CollisionWorld(cell.robot.groups, cell.workspace)
    for g in range(len(cell.robot.groups)):
        given = tools[g] if g < len(tools) else None
        world.set_tool(g, cell_tool(cell, g, cell.default_tool(g) if given is None else given))
    return world


def cell_tool(cell: CellModels, group_index: int, number: int) -> CellTool:
    """Tool file ``number`` of a group in the cell (an empty one when the cell has none)."""
    tools = cell.tools[group_index] if group_index < len(cell.tools) else ()
    return next((t for t in tools if t.number == number), CellTool(number))


__all__ = [
    "NEAR_M",
    "TOOL_LINK",
    "CollisionWorld",
    "Contact",
    "GroupBody",
    "cell_tool",
    "world_for_cell",
]
