"""Planning around the cell's obstacles: ``pymotoros plan WAYPOINTS --config CELL --avoid``.

Between each pair of waypoints OMPL (the planners MoveIt uses) searches the joint space
for a collision-free path (RRT-Connect, then shortcut simplification); a state is free
when every moving link is at least :data:`MARGIN_M` from every obstacle and the arm
does not touch itself. The resulting joint waypoints are timed as ``plan`` times any
waypoints (:func:`~pymotoros.trajectory.planning.plan_waypoints`), and the timed motion
is checked again at the controller's own increments
(:func:`~pymotoros.trajectory.collisions.find_collisions`): where the smooth path cuts a
corner into an obstacle, the segment gets its midpoint as a further waypoint and the
whole is timed again. So what this returns passes ``pymotoros check``.

A waypoint in collision, or a goal OMPL cannot reach in the time given, is a
:class:`PathBlockedError` naming the obstacle in the way (for an unreachable goal: the
first one the direct path meets).

The collision model is handed in (:class:`~pymotoros.trajectory.collisions.CollisionModel`,
built by the caller from the cell), so this layer imports no kinematics.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any, Final, Unpack

import numpy as np
import numpy.typing as npt

from pymotoros.errors import ConfigError
from pymotoros.models.cell import CellModels
from pymotoros.trajectory.check import check_against_cell
from pymotoros.trajectory.collisions import (
    CollisionModel,
    ContactLike,
    find_collisions,
)
from pymotoros.trajectory.files import Trajectory
from pymotoros.trajectory.planning import PlanTiming, plan_waypoints

F64Array = npt.NDArray[np.float64]

logger = logging.getLogger(__name__)

MARGIN_M: Final = 0.02
"""Clearance a planned state keeps from every obstacle: room for the smooth timed path
to leave the planner's straight segments a little (checked again after timing)."""
CHECK_STEP_RAD: Final = 0.03
"""The planner checks each straight segment of joint space at least this often."""
ENDPOINT_RAD: Final = 0.1
"""Within this of a waypoint (every joint) a state needs no margin, only no contact."""
DEFAULT_TIME_LIMIT_S: Final = 1.5
"""OMPL's search time per pair of waypoints before the goal counts as unreachable."""
MAX_REFINEMENTS: Final = 6
"""Rounds of "insert a midpoint where the timed path touches something, time again"."""
RNG_SEED: Final = 20261126
"""OMPL's random seed, set once per process: the same cell and waypoints plan the same."""


class PathBlockedError(ConfigError):
    """No collision-free path: a waypoint in collision, or a goal the planner cannot reach."""


_seeded = False


def _ompl() -> tuple[Any, Any]:
    """OMPL's base and geometric modules, quiet and seeded (imported on first use: it
    loads a large native library that ``plan`` without ``--avoid`` does not need)."""
    global _seeded
    from ompl import base, geometric, util

    util.setLogLevel(util.LOG_WARN)
    if not _seeded:
        util.RNG.setSeed(RNG_SEED)
        _seeded = True
    return base, geometric


def _split(q: F64Array, sizes: Sequence[int]) -> list[F64Array]:
    out, at = [], 0
    for n in sizes:
        out.append(q[at : at + n])
        at += n
    return out


class _Free:
    """Is a joint vector (every joint of the cell, groups in order) free of collisions?

    Free means :data:`MARGIN_M` from every obstacle, except near the segment's own end
    points (within :data:`ENDPOINT_RAD` on every joint): a waypoint may be closer (a
    pick from a table), and the path must be able to leave it.
    """

    def __init__(self, world: CollisionModel, sizes: Sequence[int], margin: float) -> None:
        self._world = world
        self._sizes = tuple(sizes)
        self._margin = margin
        self.ends: tuple[F64Array, ...] = ()
        self.checks = 0

    def blocking(self, q: F64Array) -> list[ContactLike]:
        """What touches at ``q``: obstacle contacts, else self-collisions (empty: free)."""
        qs = _split(q, self._sizes)
        _, contacts = self._world.probe(qs)
        if contacts:
            return [*contacts]
        return [c for c in self._world.self_distances(qs) if c.distance_m <= 0.0]

    def __call__(self, q: F64Array) -> bool:
        self.checks += 1
        qs = _split(q, self._sizes)
        clearance, contacts = self._world.probe(qs)
        near_end = any(float(np.max(np.abs(q - e))) < ENDPOINT_RAD for e in self.ends)
        if contacts or clearance <= (0.0 if near_end else self._margin):
            return False
        return all(c.distance_m > 0.0 for c in self._world.self_distances(qs))


def _describe(contacts: Sequence[ContactLike]) -> str:
    c = contacts[0]
    if c.self_collision:
        return f"{c.group} {c.link} touches {c.obstacle} (the arm itself)"
    return f"obstacle {c.obstacle!r} ({c.group} {c.link} touches it)"


def _first_on_line(free: _Free, a: F64Array, b: F64Array) -> list[ContactLike]:
    """The first contact on the straight joint path a → b (what is in the way)."""
    steps = max(2, math.ceil(float(np.max(np.abs(b - a))) / CHECK_STEP_RAD))
    for s in np.linspace(0.0, 1.0, steps + 1):
        hit = free.blocking(a + s * (b - a))
        if hit:
            return hit
    return []


def _line_is_free(free: _Free, a: F64Array, b: F64Array) -> bool:
    steps = max(2, math.ceil(float(np.max(np.abs(b - a))) / CHECK_STEP_RAD))
    return all(free(a + s * (b - a)) for s in np.linspace(0.0, 1.0, steps + 1))


def _plan_segment(
    free: _Free,
    a: F64Array,
    b: F64Array,
    lower: F64Array,
    upper: F64Array,
    time_limit_s: float,
) -> list[F64Array]:
    """A free joint path a → b (a and b included) from OMPL, simplified."""
    base, geometric = _ompl()
    n = len(a)
    space = base.RealVectorStateSpace(n)
    bounds = base.RealVectorBounds(n)
    for i in range(n):
        bounds.setLow(i, float(lower[i]))
        bounds.setHigh(i, float(upper[i]))
    space.setBounds(bounds)
    setup = geometric.SimpleSetup(space)

    def valid(state: Any) -> bool:
        return free(np.array([state[i] for i in range(n)], dtype=float))

    setup.setStateValidityChecker(valid)
    start = space.allocState()
    goal = space.allocState()
    for i in range(n):
        start[i] = float(a[i])
        goal[i] = float(b[i])
    setup.setStartAndGoalStates(start, goal)
    info = setup.getSpaceInformation()
    info.setStateValidityCheckingResolution(CHECK_STEP_RAD / space.getMaximumExtent())
    setup.setPlanner(geometric.RRTConnect(info))
    solved = setup.solve(time_limit_s)
    if not solved or not setup.haveExactSolutionPath():
        return []
    setup.simplifySolution(time_limit_s / 2)
    path = setup.getSolutionPath()
    return [
        np.array([path.getState(k)[i] for i in range(n)], dtype=float)
        for k in range(path.getStateCount())
    ]


def avoid_waypoints(
    waypoints: Sequence[Sequence[float]],
    cell: CellModels,
    world: CollisionModel,
    *,
    time_limit_s: float = DEFAULT_TIME_LIMIT_S,
) -> list[list[float]]:
    """Collision-free joint waypoints through ``waypoints`` (every joint of the cell)."""
    groups = cell.robot.groups
    sizes = [g.num_axes for g in groups]
    lower = np.array([a.lower for g in groups for a in g.axes], dtype=float)
    upper = np.array([a.upper for g in groups for a in g.axes], dtype=float)
    way = [np.asarray(w, dtype=float) for w in waypoints]
    free = _Free(world, sizes, MARGIN_M)
    for k, w in enumerate(way):
        if w.shape != (sum(sizes),):
            raise PathBlockedError(f"waypoint {k}: needs {sum(sizes)} joint values")
        hit = free.blocking(w)
        if hit:
            raise PathBlockedError(f"waypoint {k} is in collision: {_describe(hit)}")
    out: list[F64Array] = [way[0]]
    for k in range(1, len(way)):
        a, b = way[k - 1], way[k]
        free.ends = (a, b)
        if _line_is_free(free, a, b):
            out.append(b)  # the straight way keeps its margin: take it
            continue
        path = _plan_segment(free, a, b, lower, upper, time_limit_s)
        if not path:
            hit = _first_on_line(free, a, b)
            what = _describe(hit) if hit else "the cell's obstacles (no way keeps its margin)"
            raise PathBlockedError(
                f"no collision-free path from waypoint {k - 1} to {k} found in "
                f"{time_limit_s:g} s: {what} is in the way"
            )
        out.extend(path[1:])
    logger.info("avoid: %d waypoints after planning, %d collision checks", len(out), free.checks)
    return [w.tolist() for w in out]


def plan_avoiding(
    waypoints: Sequence[Sequence[float]],
    cell: CellModels,
    world: CollisionModel,
    *,
    time_limit_s: float = DEFAULT_TIME_LIMIT_S,
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
    "MARGIN_M",
    "PathBlockedError",
    "avoid_waypoints",
    "plan_avoiding",
]
