"""What the pendant's 3D view needs to draw the workspace: the robot's collision shapes
and the obstacles, both in the workspace frame (the first group's ``base_link``).

The page has no kinematics, so the shapes come placed: each group's capsules (the
``link_radii`` of its robot model, placed by the same
:class:`~pymotoros.kinematics.collision.GroupBody` the twin's contact check uses) as end
points and a radius, the tool in force (its shape from the cell file's tool data, mounted
by the same ``GroupBody.set_tool`` and with the same ``workspace.tool_radius_m`` as the
contact check, and its TCP), and each obstacle's centre, rotation and sizes, with whether
the robot touches it now (the page draws it red). Without the tool, a gripper touching a
fixture was drawn as an arm ending short of a red fixture (issue 29). All of it is
computed only when it changes: the robot's shapes when the joints or the tool change,
the obstacles when one is put or removed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import coal
import numpy as np
import pinocchio as pin

from pymotoros.controller.api import WorkspaceSnapshot
from pymotoros.controller.cell import CellConfig
from pymotoros.kinematics.collision import GroupBody
from pymotoros.models.robots import GroupKind, GroupModel, Transform
from pymotoros.models.workspace import Box, Cylinder, Obstacle, Workspace

__all__ = ["WorkspaceView"]

_DECIMALS = 4
"""0.1 mm: finer than a pixel of the view, and a short feed message."""


def _se3(frame: Transform) -> Any:
    return pin.SE3(pin.rpy.rpyToMatrix(*frame.rpy), np.array(frame.xyz, dtype=float))


def _round(values: Any) -> list[float]:
    return [round(float(v), _DECIMALS) for v in values]


def _shape_of(geometry: Any) -> tuple[str, list[float]]:
    """The page's name and sizes of a Coal shape (capsules and cylinders along z)."""
    if isinstance(geometry, coal.Capsule):
        return "capsule", _round([geometry.radius, 2 * geometry.halfLength])
    if isinstance(geometry, coal.Cylinder):
        return "cylinder", _round([geometry.radius, 2 * geometry.halfLength])
    if isinstance(geometry, coal.Box):
        return "box", _round(2 * np.asarray(geometry.halfSide, dtype=float))
    return "sphere", _round([geometry.radius])


NO_TOOL: Final = Transform()
"""A TCP on tool0 and no shape: the body with its links only."""


@dataclass(frozen=True, slots=True)
class _Mount:
    """A tool file mounted on a group: placements on the last joint's frame."""

    number: int
    name: str
    tool0: Any
    tcp: Any
    shape: tuple[str, list[float], Any] | None
    """The collision shape's kind, sizes and placement (None: no shape)."""


Placed = tuple[list[list[float]], dict[str, Any] | None]
"""A group's capsules and its tool (see :meth:`WorkspaceView.robot`)."""


class WorkspaceView:
    """The placed shapes of one cell, for the pendant's document."""

    def __init__(self, cell: CellConfig | None) -> None:
        self._cell = cell
        self._workspace: Workspace = cell.workspace if cell is not None else Workspace()
        self._bodies: list[GroupBody | None] = []
        self._groups: list[GroupModel] = list(cell.groups) if cell is not None else []
        for group in cell.groups if cell else ():
            shaped = group.kind is GroupKind.ROBOT  # base and station axes have no shapes
            self._bodies.append(
                GroupBody(
                    group,
                    self._workspace.base(group.name),
                    tool_radius=self._workspace.tool_radius_m,  # as the contact check's
                )
                if shaped
                else None
            )
        self._placed_robot: dict[int, tuple[tuple[Any, ...], Placed]] = {}
        self._mounts: dict[tuple[int, int], _Mount] = {}
        """(group, tool number) → the tool on the last joint's frame."""
        self._obstacles_key: tuple[Obstacle, ...] | None = None
        self._placed: list[dict[str, Any]] = []

    def robot(self, group_index: int, q: Sequence[float], tool: int) -> Placed | None:
        """The group at joints ``q`` with tool file ``tool`` in force: its link capsules
        (``[ax, ay, az, bx, by, bz, radius]`` each, m, the tool's shape not among them)
        and the tool (:meth:`_tool`); None for a group without collision shapes. Do not
        mutate the answer: it is reused while the joints and the tool stay."""
        body = self._bodies[group_index] if group_index < len(self._bodies) else None
        if body is None or self._cell is None or len(q) != body.num_joints:
            return None
        key = (*q, tool)
        known = self._placed_robot.get(group_index)
        if known is not None and known[0] == key:
            return known[1]
        mount = self._mount(self._cell, group_index, body, tool)
        parts = body.place(np.asarray(q, dtype=float))  # the links only (see _mount)
        capsules = [
            [*_round(ends[0]), *_round(ends[1]), round(part.radius, _DECIMALS)]
            for part, ends in zip(parts, body.ends, strict=True)
        ]
        placed: Placed = (capsules, self._tool(body, mount))
        self._placed_robot[group_index] = (key, placed)
        return placed

    def _mount(self, cell: CellConfig, group_index: int, body: GroupBody, number: int) -> _Mount:
        """Tool file ``number`` of the group as the twin's contact check mounts it
        (``GroupBody.set_tool``: the same shape, the same tool radius), kept as placements
        on the last joint's frame. Built once per group and tool; the body itself is left
        without a tool, so placing it moves the links only (a mounted tool would make
        every ``place`` rebuild the body's stacked end points)."""
        mount = self._mounts.get((group_index, number))
        if mount is not None:
            return mount
        tool = cell.tool(group_index, number).cell_tool
        body.set_tool(tool)
        part = body.tool_part
        body.set_tool(NO_TOOL)  # back to the bare links (no shape, TCP on tool0)
        group = self._groups[group_index]
        tool0 = _se3(group.tool0) if group.tool0 is not None else pin.SE3.Identity()
        shape = None if part is None else (*_shape_of(part.geometry), part.local)
        mount = _Mount(tool.number, tool.name, tool0, tool0 * _se3(tool.tcp), shape)
        self._mounts[(group_index, number)] = mount
        return mount

    @staticmethod
    def _tool(body: GroupBody, mount: _Mount) -> dict[str, Any]:
        """The tool in force, placed (workspace frame): ``number``, ``name``, ``shape``
        (capsule, box, cylinder, sphere; null for a tool whose TCP is tool0 and that has
        no shape), ``size`` (a capsule's or cylinder's radius and length along its own z,
        a box's full sizes, a sphere's radius), ``xyz`` and ``rot`` (3 × 3, row by row)
        of the shape's centre, and the points ``tool0`` and ``tcp``."""
        last = body.frames[body.num_joints - 1]  # the last joint's frame, workspace frame
        out: dict[str, Any] = {
            "number": mount.number,
            "name": mount.name,
            "shape": None,
            "tool0": _round((last * mount.tool0).translation),
            "tcp": _round((last * mount.tcp).translation),
        }
        if mount.shape is None:
            return out
        kind, size, local = mount.shape
        m = last * local
        out |= {
            "shape": kind,
            "size": size,
            "xyz": _round(m.translation),
            "rot": _round(np.asarray(m.rotation, dtype=float).reshape(9)),
        }
        return out

    def obstacles(self, workspace: WorkspaceSnapshot) -> list[dict[str, Any]]:
        """Each obstacle placed in the workspace frame: ``name``, ``shape`` (box, cylinder,
        sphere), ``size`` (the box's full sizes; the cylinder's radius and length; the
        sphere's radius), ``xyz`` and ``rot`` (3 × 3, row by row), and ``contact``."""
        if workspace.obstacles is not self._obstacles_key:
            self._obstacles_key = workspace.obstacles
            self._placed = [self._place(o) for o in workspace.obstacles]
        touched = {c.obstacle for c in workspace.contacts if not c.self_collision}
        return [{**o, "contact": o["name"] in touched} for o in self._placed]

    def _place(self, obstacle: Obstacle) -> dict[str, Any]:
        m = _se3(obstacle.pose)
        if obstacle.frame:
            m = _se3(self._workspace.base(obstacle.frame)) * m
        shape = obstacle.shape
        if isinstance(shape, Box):
            kind, size = "box", list(shape.size)
        elif isinstance(shape, Cylinder):
            kind, size = "cylinder", [shape.radius, shape.length]
        else:
            kind, size = "sphere", [shape.radius]
        return {
            "name": obstacle.name,
            "shape": kind,
            "size": size,
            "xyz": _round(m.translation),
            "rot": _round(np.asarray(m.rotation, dtype=float).reshape(9)),
        }
