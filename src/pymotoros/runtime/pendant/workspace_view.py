"""What the pendant's 3D view needs to draw the workspace: the robot's collision shapes
and the obstacles, both in the workspace frame (the first group's ``base_link``).

The page has no kinematics, so the shapes come placed: each group's capsules (the link
shapes of :mod:`pymotoros.models.link_shapes`, placed by the same
:class:`~pymotoros.kinematics.collision.GroupBody` the twin's contact check uses) as end
points and a radius, and each obstacle's centre, rotation and sizes, with whether the
robot touches it now (the page draws it red). Both are computed only when they change:
the capsules when the joints move, the obstacles when one is put or removed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from pymotoros.controller.api import WorkspaceSnapshot
from pymotoros.controller.cell import CellConfig
from pymotoros.kinematics.collision import GroupBody
from pymotoros.models.link_shapes import link_radii
from pymotoros.models.robots import Transform
from pymotoros.models.workspace import Box, Cylinder, Obstacle, Workspace

__all__ = ["WorkspaceView"]

_DECIMALS = 4
"""0.1 mm: finer than a pixel of the view, and a short feed message."""


def _se3(frame: Transform) -> Any:
    return pin.SE3(pin.rpy.rpyToMatrix(*frame.rpy), np.array(frame.xyz, dtype=float))


def _round(values: Any) -> list[float]:
    return [round(float(v), _DECIMALS) for v in values]


class WorkspaceView:
    """The placed shapes of one cell, for the pendant's document."""

    def __init__(self, cell: CellConfig | None) -> None:
        self._workspace: Workspace = cell.workspace if cell is not None else Workspace()
        self._bodies: list[GroupBody | None] = []
        for group, robot in zip(cell.groups, cell.robots, strict=True) if cell else ():
            shaped = link_radii(robot, group) is not None and all(
                a.geometry is not None for a in group.axes
            )
            self._bodies.append(
                GroupBody(group, robot, self._workspace.base(group.name)) if shaped else None
            )
        self._capsules: dict[int, tuple[tuple[float, ...], list[list[float]]]] = {}
        self._obstacles_key: tuple[Obstacle, ...] | None = None
        self._placed: list[dict[str, Any]] = []

    def capsules(self, group_index: int, q: Sequence[float]) -> list[list[float]] | None:
        """The group's capsules at joints ``q``: ``[ax, ay, az, bx, by, bz, radius]`` each
        (m); None for a group without collision shapes. Do not mutate the answer."""
        body = self._bodies[group_index] if group_index < len(self._bodies) else None
        if body is None or len(q) != body.num_joints:
            return None
        key = tuple(q)
        known = self._capsules.get(group_index)
        if known is not None and known[0] == key:
            return known[1]
        parts = body.place(np.asarray(key, dtype=float))
        out = [
            [*_round(ends[0]), *_round(ends[1]), round(part.radius, _DECIMALS)]
            for part, ends in zip(parts, body.ends, strict=True)
        ]
        self._capsules[group_index] = (key, out)
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
