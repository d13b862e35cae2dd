"""Planning around the cell's obstacles: ``pymotoros plan WAYPOINTS --config CELL --avoid``.

Between each pair of waypoints OMPL (the planners MoveIt uses) searches the joint space
for a collision-free path (RRT-Connect, then shortcut simplification); a state is free
when every moving link is at least 2 cm from every obstacle and the arm does not touch
itself. The search is the collision model's (:meth:`CollisionModel.free_waypoints`:
``kinematics/path_search.py``, which the client's ``move_joints(..., avoid=True)`` uses
too). The resulting joint waypoints are timed as ``plan`` times any waypoints
(:func:`~pymotoros.trajectory.planning.plan_waypoints`), and the timed motion is checked
again at the controller's own increments
(:func:`~pymotoros.trajectory.collisions.find_collisions`): where the smooth path cuts a
corner into an obstacle, the segment gets its midpoint as a further waypoint and the
whole is timed again. So what this returns passes ``pymotoros check``.

A waypoint in collision, or a goal OMPL cannot reach in the time given, is a
:class:`~pymotoros.errors.PathBlockedError` naming the obstacle in the way (for an
unreachable goal: the first one the direct path meets).

The collision model is handed in (:class:`~pymotoros.trajectory.collisions.CollisionModel`,
built by the caller from the cell), so this layer imports no kinematics.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Final, Unpack

import numpy as np
import numpy.typing as npt

from pymotoros.errors import PathBlockedError
from pymotoros.models.cell import CellModels
from pymotoros.trajectory.check import check_against_cell
from pymotoros.trajectory.collisions import CollisionModel, find_collisions
from pymotoros.trajectory.files import Trajectory
from pymotoros.trajectory.planning import PlanTiming, plan_waypoints

F64Array = npt.NDArray[np.float64]

logger = logging.getLogger(__name__)

MAX_REFINEMENTS: Final = 6
"""Rounds of "insert a midpoint where the timed path touches something, time again"."""


def avoid_waypoints(
    waypoints: Sequence[Sequence[float]],
    cell: CellModels,
    world: CollisionModel,
    *,
    time_limit_s: float | None = None,
) -> list[list[float]]:
    """Collision-free joint waypoints through ``waypoints`` (every joint of the cell):
    the collision model's own search (OMPL, see the module docstring); ``time_limit_s``
    per pair of waypoints (None: the search's default, 1.5 s)."""
    count = sum(g.num_axes for g in cell.robot.groups)
    for k, w in enumerate(waypoints):
        if len(w) != count:
            raise PathBlockedError(f"waypoint {k}: needs {count} joint values")
    return world.free_waypoints(waypoints, time_limit_s=time_limit_s)


def plan_avoiding(
    waypoints: Sequence[Sequence[float]],
    cell: CellModels,
    world: CollisionModel,
    *,
    time_limit_s: float | None = None,
    **timing: Unpack[PlanTiming],
) -> Trajectory:
    """A timed trajectory through ``waypoints`` around the cell's obstacles, checked at
    the controller's increments (see the module docstring). ``timing``: as
    :func:`plan_waypoints` (velocity_scaling, acceleration_scaling, sample_s)."""
    way = avoid_waypoints(waypoints, cell, world, time_limit_s=time_limit_s)
    for _ in range(MAX_REFINEMENTS):
        traj = plan_waypoints(way, cell.robot, cell.controller, **timing)
        report = check_against_cell(traj, cell)
        hits = find_collisions(traj, cell, report.per_group, world) if report.accepted else []
        if not hits:
            return traj
        way = _refine(way, traj, hits[0].time_s)
    raise PathBlockedError(
        f"the timed path still touches {hits[0].obstacle!r} ({hits[0].link}) at "
        f"{hits[0].time_s:.3f} s after {MAX_REFINEMENTS} refinements; add a waypoint "
        "farther from it"
    )


def _refine(way: list[list[float]], traj: Trajectory, time_s: float) -> list[list[float]]:
    """Insert the midpoint of the waypoint segment the motion is on at ``time_s``."""
    q = traj.positions[int(np.searchsorted(traj.times, time_s).clip(0, len(traj.times) - 1))]
    arr = np.asarray(way, dtype=float)
    # the segment whose straight line passes nearest the pose at the contact
    best, best_d = 1, math.inf
    for k in range(1, len(arr)):
        a, b = arr[k - 1], arr[k]
        ab = b - a
        s = float(np.clip(np.dot(q - a, ab) / max(float(np.dot(ab, ab)), 1e-12), 0.0, 1.0))
        d = float(np.linalg.norm(a + s * ab - q))
        if d < best_d:
            best, best_d = k, d
    mid = ((arr[best - 1] + arr[best]) / 2.0).tolist()
    return [*way[:best], mid, *way[best:]]


__all__ = [
    "PathBlockedError",
    "avoid_waypoints",
    "plan_avoiding",
]
