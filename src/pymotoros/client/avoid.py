"""The cell's obstacles in the client: the guard of every move, and moves around them.

**The guard** (:meth:`Avoidance.check`): before anything is sent, every move of a client
whose cell file has obstacles (joint, named, pose, straight line, relative, a user's
``execute``) is sampled at every interpolation tick as MotoROS interpolates it
(:func:`tick_positions`) and checked by :func:`pymotoros.kinematics.sweep.sweep`; a move
that would touch something is a :class:`PathBlockedError` naming time, link, obstacle
and depth, unless it only backs the robot out of a contact it starts in (the rule:
:mod:`pymotoros.kinematics.sweep`). After a move a contact stopped,
:meth:`Avoidance.contact_at` names what the robot touches where it stands.

**Around the obstacles**: ``move_joints(..., avoid=True)``, ``move_pose(..., avoid=True)``,
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

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Final

from pymotoros.client.guard import (
    FORCE_HINT,
    contact_words,
    names,
    start_contacts,
    stuck_refusal,
    tick_positions,
)
from pymotoros.client.planning import JointLimits, JointTrajectory, PlanningError, plan_joint_move
from pymotoros.client.tools import ToolTable
from pymotoros.errors import PathBlockedError
from pymotoros.log_tags import AS_NOTE
from pymotoros.models.cell import CellModels

if TYPE_CHECKING:  # Pinocchio, Coal and OMPL load only when a move avoids something
    import numpy as np
    import numpy.typing as npt

    from pymotoros.kinematics.collision import CollisionWorld

logger = logging.getLogger(__name__)

LABELS: Final = ("the start", "the goal")
"""How a refusal names the two ends of the move."""
ESCAPE_STEP_RAD: Final = 0.01
"""Joint step of the way out of a contact that ``avoid`` takes before its search."""
ESCAPE_MAX_RAD: Final = 0.5
"""Farthest (largest joint travel, 29°) ``avoid`` looks for the way out of a contact."""
ESCAPE_CLEARANCE_M: Final = 0.005
"""Clearance (5 mm) at which the way out of a contact ends and the search begins."""


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

    def _mount_tools(self, world: CollisionWorld, tools: Mapping[int, int] | None = None) -> None:
        """Each group's tool on its flange: the move's own tool (``tools``: group index ->
        tool number, the ``tool=`` of a Cartesian move, whose TCP the move was planned
        with), else the tool in force as this client knows it, else the one the cell
        boots with (what the twin and ``check`` assume too)."""
        cell = self._cell
        for g in range(len(world.groups)):
            number = (tools or {}).get(g, self._tools.selected.get(g))
            if number is None and cell is not None:
                number = cell.default_tool(g)
            world.set_tool(g, self._tools.tool(g, number or 0))

    @property
    def guards(self) -> bool:
        """Whether moves are checked at all: the client has a cell with obstacles."""
        return self._cell is not None and bool(self._cell.workspace.obstacles)

    def _joined(
        self,
        world: CollisionWorld,
        moving: Sequence[int],
        standing: Sequence[Sequence[float] | None],
    ) -> tuple[list[int], list[float]]:
        """(columns of the moving groups, in the order of ``moving`` (a trajectory's
        joints), in a joint vector of every group of the cell; that vector with the
        groups where they stand: their feedback, else their home)."""
        offsets = [sum(world.joint_counts[:g]) for g in range(len(world.groups))]
        columns = [offsets[g] + i for g in moving for i in range(world.groups[g].num_axes)]
        joined: list[float] = []
        for g, group in enumerate(world.groups):
            here = standing[g] if g < len(standing) else None
            joined.extend(here if here is not None else group.home)
        return columns, joined

    def check(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        standing: Sequence[Sequence[float] | None],
        period_s: float,
        tools: Mapping[int, int] | None = None,
    ) -> str | None:
        """The guard of every move the client makes (docs/workspace.md): ``trajectory``
        (the joints of ``groups``; the other groups stand at ``standing``) sampled at
        every interpolation tick (``period_s``) as MotoROS interpolates it, checked
        against the cell's obstacles and the arm itself with each group's tool
        (``tools``: the move's own tool per group index, over the one in force).

        Raises :class:`PathBlockedError` naming the first contact (time, link, obstacle,
        depth) and what to do; a move that starts in contact and only backs out of it is
        allowed, and the note saying so is returned (and logged). Nothing is sent either
        way: the caller streams only after this returns."""
        import numpy as np

        from pymotoros.kinematics.sweep import sweep

        if len(trajectory.points) <= 1:  # one point or none: nothing moves
            return None
        world = self.world()
        self._mount_tools(world, tools)
        columns, joined = self._joined(world, groups, standing)
        times, ticks = tick_positions(trajectory, period_s)
        full = np.tile(np.asarray(joined, dtype=float), (len(times), 1))
        full[:, columns] = ticks
        found = sweep(world, times, full, world.joint_counts)
        blocking = found.blocking
        if not blocking:
            if found.starts_in_contact:
                note = (
                    f"the robot starts touching {names(start_contacts(found))}; this move "
                    "only takes it away (the clearance grows all along the move), so it is "
                    "allowed"
                )
                logger.warning("%s", note, extra=AS_NOTE)  # the CLI: a `note: …` line
                return note
            return None
        if found.starts_in_contact and not found.receding:
            refusal = stuck_refusal(world, self._tools, found, full[0], columns, tools)
            raise PathBlockedError(refusal)
        first = blocking[0]
        more = f" (and {len(blocking) - 1} more)" if len(blocking) > 1 else ""
        raise PathBlockedError(
            f"the planned move would hit: {first.text()}{more}; nothing was sent. Plan "
            "around it (--avoid, avoid=True), move the goal or the obstacle, "
            f"{FORCE_HINT}"
        )

    def contact_at(self, standing: Sequence[Sequence[float] | None]) -> str | None:
        """What the robot touches (or nearly) where it stands, in words with distances
        in mm (:func:`~pymotoros.client.guard.contact_words`); None without obstacles or
        when nothing is near. Named in the error of a move a collision alarm stopped."""
        if not self.guards or any(q is None for q in standing):
            return None
        import numpy as np

        from pymotoros.kinematics.path_search import split

        world = self.world()
        self._mount_tools(world)
        _, joined = self._joined(world, (), standing)
        return contact_words(world, split(np.asarray(joined, dtype=float), world.joint_counts))

    def _way_out(
        self, world: CollisionWorld, a: Sequence[float], b: Sequence[float], moving: set[int]
    ) -> list[float] | None:
        """Where ``avoid`` leaves a contact the robot starts in (None: it starts clear):
        the nearest joint state, straight towards the goal or along one joint of a moving
        group, reached while the clearance only grows and :data:`ESCAPE_CLEARANCE_M` from
        every obstacle. A :class:`PathBlockedError` when no such way is found."""
        import numpy as np

        from pymotoros.kinematics.path_search import describe, split
        from pymotoros.kinematics.sweep import RECEDE_TOLERANCE_M

        sizes = world.joint_counts
        qa = np.asarray(a, dtype=float)
        here, contacts = world.probe(split(qa, sizes))
        if not contacts:
            return None
        columns, _ = self._joined(world, sorted(moving), [None] * len(world.groups))
        toward = np.asarray(b, dtype=float) - qa
        directions = []
        if float(np.max(np.abs(toward))) > 0.0:
            directions.append(toward / float(np.max(np.abs(toward))))
        for c in columns:
            for sign in (1.0, -1.0):
                d = np.zeros(len(qa))
                d[c] = sign
                directions.append(d)
        axes = [ax for g in world.groups for ax in g.axes]
        best: tuple[float, npt.NDArray[np.float64]] | None = None
        for d in directions:
            previous = here
            for k in range(1, int(ESCAPE_MAX_RAD / ESCAPE_STEP_RAD) + 1):
                q = qa + d * ESCAPE_STEP_RAD * k
                if any(not ax.lower <= v <= ax.upper for ax, v in zip(axes, q, strict=True)):
                    break
                clearance, _ = world.probe(split(q, sizes))
                if clearance < previous - RECEDE_TOLERANCE_M:
                    break  # deeper: not a way out
                previous = clearance
                if clearance >= ESCAPE_CLEARANCE_M:
                    travel = ESCAPE_STEP_RAD * k
                    if best is None or travel < best[0]:
                        best = (travel, q)
                    break
        if best is None:
            raise PathBlockedError(
                f"the start is in collision: {describe(contacts)}, and no joint move within "
                f"{math.degrees(ESCAPE_MAX_RAD):.0f}° leaves it while the clearance only "
                f"grows; back out by hand (a jog on the pendant), {FORCE_HINT}"
            )
        logger.info("avoid: leaving the contact at the start over %.3f rad first", best[0])
        return [float(v) for v in best[1]]

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
        tools: Mapping[int, int] | None = None,
    ) -> JointTrajectory:
        """A move of ``groups`` from ``start`` to ``goal`` around the obstacles (both per
        group of the cell: the groups that do not move stand where they are, and the
        search moves only ``groups``), timed within ``limits`` (those of ``groups``);
        ``tools`` as in :meth:`check`."""
        world = self.world()
        self._mount_tools(world, tools)
        moving = set(groups)
        a = [float(v) for q in start for v in q]
        b = [float(v) for q in goal for v in q]
        escape = self._way_out(world, a, b, moving)
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
            [escape or a, b], lower=lower, upper=upper, labels=LABELS, time_limit_s=time_limit_s
        )
        if escape is not None:  # out of the contact first (checked by guard(): receding)
            path.insert(0, a)
        for k in range(1 + (escape is not None), len(path)):
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
