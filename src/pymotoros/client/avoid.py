"""Joint moves around the cell's obstacles: ``move_joints(..., avoid=True)``,
``plan(..., avoid=True)`` and ``pymotoros move --avoid``.

The client speaks only the wire, and MotoROS knows nothing of obstacles, so the client
takes them from the cell file it was given (``RobotClient(cell=...)``, ``--config``:
``[workspace]``, docs/workspace.md). The path is searched by the same OMPL search as
``pymotoros plan --avoid`` (:meth:`CollisionWorld.free_waypoints`,
``kinematics/path_search.py``): straight joint segments between states that keep 2 cm
from every obstacle and do not touch the arm itself.

Timing: each segment is a rest-to-rest ruckig move (:func:`plan_joint_move`), a
straight line in joint space, so the robot follows exactly the segments the search
checked (MotoROS's cubic between two points of one straight segment stays on it); every
segment is also checked continuously (:meth:`CollisionWorld.segment_contacts`) before
anything is sent. The robot stops briefly at each corner of the path: a detour costs a
few tenths of a second more than a smooth one (``pymotoros plan --avoid`` times the
path smoothly, and checks it at the controller's increments).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Final

from pymotoros.client.planning import JointLimits, JointTrajectory, PlanningError, plan_joint_move
from pymotoros.client.tools import ToolTable
from pymotoros.errors import PathBlockedError
from pymotoros.models.cell import CellModels

if TYPE_CHECKING:  # Pinocchio, Coal and OMPL load only when a move avoids something
    from pymotoros.kinematics.collision import CollisionWorld

LABELS: Final = ("the start", "the goal")
"""How a refusal names the two ends of the move."""


class Avoidance:
    """The cell's obstacles as the client knows them, and moves planned around them."""

    def __init__(self, cell: CellModels | None, tools: ToolTable) -> None:
        self._cell = cell
        self._tools = tools
        self._world: CollisionWorld | None = None

    def world(self) -> CollisionWorld:
        """The collision model of the client's cell, with each group's tool (built once)."""
        cell = self._cell
        if cell is None:
            raise PlanningError(
                "avoid=True needs the cell's obstacles, which MotoROS cannot report: give "
                "the client the cell file (RobotClient(cell=...), --config CELL.toml)"
            )
        if self._world is None:
            from pymotoros.kinematics.collision import world_for_cell

            self._world = world_for_cell(cell)
        return self._world

    def _mount_tools(self, world: CollisionWorld) -> None:
        """Each group's tool on its flange: the tool in force as this client knows it,
        else the one the cell boots with (what the twin and ``check`` assume too)."""
        cell = self._cell
        for g in range(len(world.groups)):
            number = self._tools.selected.get(g)
            if number is None and cell is not None:
                number = cell.default_tool(g)
            world.set_tool(g, self._tools.tool(g, number or 0))

    def plan(
        self,
        start: Sequence[Sequence[float]],
        goal: Sequence[Sequence[float]],
        groups: Sequence[int],
        limits: JointLimits,
        *,
        velocity_scaling: float,
        acceleration_scaling: float,
        sample_period: float,
        time_limit_s: float | None = None,
    ) -> JointTrajectory:
        """A move of ``groups`` from ``start`` to ``goal`` around the obstacles (both per
        group of the cell: the groups that do not move stand where they are, and the
        search moves only ``groups``), timed within ``limits`` (those of ``groups``)."""
        world = self.world()
        self._mount_tools(world)
        moving = set(groups)
        a = [float(v) for q in start for v in q]
        b = [float(v) for q in goal for v in q]
        lower: list[float] = []
        upper: list[float] = []
        columns: list[int] = []
        for g, group in enumerate(world.groups):
            at = len(lower)
            if g in moving:
                lower.extend(axis.lower for axis in group.axes)
                upper.extend(axis.upper for axis in group.axes)
            else:  # a group that does not move is held where it stands
                lower.extend(a[at : at + group.num_axes])
                upper.extend(a[at : at + group.num_axes])
        for g in sorted(moving):
            at = sum(world.joint_counts[:g])
            columns.extend(range(at, at + world.joint_counts[g]))
        path = world.free_waypoints(
            [a, b], lower=lower, upper=upper, labels=LABELS, time_limit_s=time_limit_s
        )
        for k in range(1, len(path)):
            hit = world.segment_contacts(path[k - 1], path[k])
            if hit:
                from pymotoros.kinematics.path_search import describe

                raise PathBlockedError(
                    f"the path found from the start to the goal touches {describe(hit)} "
                    f"on its segment {k} of {len(path) - 1}; move the goal or the obstacle"
                )
        pieces = [
            plan_joint_move(
                [path[k - 1][c] for c in columns],
                [path[k][c] for c in columns],
                limits,
                velocity_scaling=velocity_scaling,
                acceleration_scaling=acceleration_scaling,
                sample_period=sample_period,
            )
            for k in range(1, len(path))
        ]
        return join(pieces)


def join(pieces: Sequence[JointTrajectory]) -> JointTrajectory:
    """Rest-to-rest moves one after the other as one trajectory (each corner once)."""
    points = list(pieces[0].points)
    optimal = pieces[0].optimal_duration
    for piece in pieces[1:]:
        offset = points[-1].time
        points.extend(replace(p, time=p.time + offset) for p in piece.points[1:])
        optimal += piece.optimal_duration
    return JointTrajectory(tuple(points), optimal)


__all__ = ["Avoidance", "join"]
