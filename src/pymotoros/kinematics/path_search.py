"""A collision-free joint path through waypoints, searched by OMPL: the one search behind
``pymotoros plan --avoid`` and ``move --avoid`` and the client's ``move_joints(...,
avoid=True)``.

Both users need it: the trajectory layer (``trajectory/avoid.py``, which takes it through
:meth:`~pymotoros.kinematics.collision.CollisionWorld.free_waypoints`, so that it imports
no kinematics) and the client (which may import the kinematics but not the trajectory
layer), so it lives here beside the collision model it asks.

Between each pair of waypoints whose straight joint path is not free, OMPL's RRT-Connect
(the planner MoveIt uses by default) searches for a path whose states keep
:data:`MARGIN_M` from every obstacle (less near the waypoints themselves, so a pick close
to a table works) and do not touch the arm itself, then shortcuts it. A waypoint in
collision, or a goal the search cannot reach in its time, is a
:class:`~pymotoros.errors.PathBlockedError` naming the obstacle in the way (for an
unreachable goal: the first one the straight path meets).

:func:`segment_contacts` checks a straight joint segment continuously (conservative
advancement: after a probe finds the robot ``c`` metres from everything, no point of it
can touch before it has moved ``c``, and each joint moves no point farther than its
reach per radian), for a caller that moves along the straight segments themselves.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any, Final, Protocol

import numpy as np
import numpy.typing as npt

from pymotoros.errors import PathBlockedError
from pymotoros.models.workspace import ContactLike

F64Array = npt.NDArray[np.float64]

logger = logging.getLogger(__name__)

MARGIN_M: Final = 0.02
"""Clearance a planned state keeps from every obstacle: room for a smooth timed path to
leave the planner's straight segments a little (``plan --avoid`` checks again after
timing), and for the straight segments between two checked states."""
CHECK_STEP_RAD: Final = 0.03
"""The planner checks each straight segment of joint space at least this often."""
ENDPOINT_RAD: Final = 0.1
"""Within this of a waypoint (every joint) a state needs no margin, only no contact."""
DEFAULT_TIME_LIMIT_S: Final = 1.5
"""OMPL's search time per pair of waypoints before the goal counts as unreachable."""
RNG_SEED: Final = 20261126
"""OMPL's random seed, set once per process: the same cell and waypoints plan the same."""
MIN_ADVANCE_M: Final = 1e-4
"""The continuous check's smallest step (m of travel): a path grazing an obstacle closer
than this is not a contact, and the check ends."""


class SearchWorld(Protocol):
    """What the search asks of the collision model
    (:class:`~pymotoros.kinematics.collision.CollisionWorld` is one)."""

    def probe(self, qs: Sequence[F64Array]) -> tuple[float, Sequence[ContactLike]]: ...
    def self_distances(self, qs: Sequence[F64Array]) -> Sequence[ContactLike]: ...
    def joint_reach(self, group_index: int) -> list[float]: ...


_seeded = False


def _ompl() -> tuple[Any, Any]:
    """OMPL's base and geometric modules, quiet and seeded (imported on first use: it
    loads a large native library that nothing else needs)."""
    global _seeded
    from ompl import base, geometric, util

    util.setLogLevel(util.LOG_WARN)
    if not _seeded:
        util.RNG.setSeed(RNG_SEED)
        _seeded = True
    return base, geometric


def split(q: F64Array, sizes: Sequence[int]) -> list[F64Array]:
    """A joint vector of every group (one after the other) as one vector per group."""
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

    def __init__(self, world: SearchWorld, sizes: Sequence[int], margin: float) -> None:
        self._world = world
        self._sizes = tuple(sizes)
        self._margin = margin
        self.ends: tuple[F64Array, ...] = ()
        self.checks = 0

    def blocking(self, q: F64Array) -> list[ContactLike]:
        """What touches at ``q``: obstacle contacts, else self-collisions (empty: free)."""
        qs = split(q, self._sizes)
        _, contacts = self._world.probe(qs)
        if contacts:
            return [*contacts]
        return [c for c in self._world.self_distances(qs) if c.distance_m <= 0.0]

    def __call__(self, q: F64Array) -> bool:
        self.checks += 1
        qs = split(q, self._sizes)
        clearance, contacts = self._world.probe(qs)
        near_end = any(float(np.max(np.abs(q - e))) < ENDPOINT_RAD for e in self.ends)
        if contacts or clearance <= (0.0 if near_end else self._margin):
            return False
        return all(c.distance_m > 0.0 for c in self._world.self_distances(qs))


def describe(contacts: Sequence[ContactLike]) -> str:
    """The first contact in words: ``obstacle 'ball' (R1 link_2_l touches it)``."""
    c = contacts[0]
    if c.self_collision:
        return f"{c.group} {c.link} touches {c.obstacle} (the arm itself)"
    return f"obstacle {c.obstacle!r} ({c.group} {c.link} touches it)"


def _steps(a: F64Array, b: F64Array) -> F64Array:
    count = max(2, math.ceil(float(np.max(np.abs(b - a))) / CHECK_STEP_RAD))
    return np.linspace(0.0, 1.0, count + 1)


def _first_on_line(free: _Free, a: F64Array, b: F64Array) -> list[ContactLike]:
    """The first contact on the straight joint path a → b (what is in the way)."""
    for s in _steps(a, b):
        hit = free.blocking(a + s * (b - a))
        if hit:
            return hit
    return []


def _line_is_free(free: _Free, a: F64Array, b: F64Array) -> bool:
    return all(free(a + s * (b - a)) for s in _steps(a, b))


def _plan_segment(
    free: _Free,
    a: F64Array,
    b: F64Array,
    lower: F64Array,
    upper: F64Array,
    time_limit_s: float,
) -> list[F64Array]:
    """A free joint path a → b (a and b included) from OMPL, simplified ([]: none found)."""
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


def free_waypoints(
    world: SearchWorld,
    waypoints: Sequence[Sequence[float]],
    sizes: Sequence[int],
    lower: Sequence[float],
    upper: Sequence[float],
    *,
    time_limit_s: float = DEFAULT_TIME_LIMIT_S,
    labels: Sequence[str] = (),
) -> list[list[float]]:
    """Collision-free joint waypoints through ``waypoints`` (every joint of every group
    of ``world``, ``sizes`` joints per group), searched within ``lower`` … ``upper``;
    ``labels`` name the waypoints in a refusal (default ``waypoint 0``, ``waypoint 1`` …)."""
    count = sum(sizes)
    low = np.asarray(lower, dtype=float)
    high = np.asarray(upper, dtype=float)
    way = [np.asarray(w, dtype=float) for w in waypoints]

    def label(k: int) -> str:
        return labels[k] if k < len(labels) else f"waypoint {k}"

    free = _Free(world, sizes, MARGIN_M)
    for k, w in enumerate(way):
        if w.shape != (count,):
            raise PathBlockedError(f"{label(k)}: needs {count} joint values")
        hit = free.blocking(w)
        if hit:
            raise PathBlockedError(f"{label(k)} is in collision: {describe(hit)}")
    out: list[F64Array] = [way[0]]
    for k in range(1, len(way)):
        a, b = way[k - 1], way[k]
        free.ends = (a, b)
        if _line_is_free(free, a, b):
            out.append(b)  # the straight way keeps its margin: take it
            continue
        path = _plan_segment(free, a, b, low, high, time_limit_s)
        if not path:
            hit = _first_on_line(free, a, b)
            what = describe(hit) if hit else "the cell's obstacles (no way keeps its margin)"
            between = f"{label(k - 1)} to {label(k)}" if labels else f"waypoint {k - 1} to {k}"
            raise PathBlockedError(
                f"no collision-free path from {between} found in {time_limit_s:g} s: "
                f"{what} is in the way"
            )
        out.extend(path[1:])
    logger.info("avoid: %d waypoints after planning, %d collision checks", len(out), free.checks)
    return [w.tolist() for w in out]


def segment_contacts(
    world: SearchWorld, a: Sequence[float], b: Sequence[float], sizes: Sequence[int]
) -> list[ContactLike]:
    """The first contact (obstacle or self-collision) anywhere on the straight joint
    path a → b, or [] when it is free all the way (see the module docstring)."""
    qa = np.asarray(a, dtype=float)
    delta = np.asarray(b, dtype=float) - qa
    # metres any point of the robot moves at most per unit of the way from a to b
    rate = max(
        (
            float(np.abs(d) @ np.asarray(world.joint_reach(g), dtype=float))
            for g, d in enumerate(split(delta, sizes))
            if world.joint_reach(g)
        ),
        default=0.0,
    )
    s = 0.0
    while True:
        qs = split(qa + s * delta, sizes)
        clearance, contacts = world.probe(qs)
        if contacts:
            return [*contacts]
        distances = world.self_distances(qs)
        touching = [c for c in distances if c.distance_m <= 0.0]
        if touching:
            return touching
        if s >= 1.0 or rate <= 0.0:
            return []
        # two links of one arm approach each other at most twice as fast
        own = min((c.distance_m for c in distances), default=math.inf) / 2.0
        s = min(1.0, s + max(min(clearance, own), MIN_ADVANCE_M) / rate)


__all__ = [
    "CHECK_STEP_RAD",
    "DEFAULT_TIME_LIMIT_S",
    "ENDPOINT_RAD",
    "MARGIN_M",
    "ContactLike",
    "SearchWorld",
    "describe",
    "free_waypoints",
    "segment_contacts",
    "split",
]
