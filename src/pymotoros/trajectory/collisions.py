"""Collisions along a checked trajectory: the robot against the cell's obstacles and itself.

``pymotoros check TRAJ --config CELL`` replays the motion at the controller's own
increments (:attr:`CheckReport.per_group`, exactly what IncMove would execute), so a
table clipped between two points is found, not only at the points. Each contact is
reported once, at the first tick it starts, with the obstacle (or, for a
self-collision, the other link), the link and the time.

Cost: a full check of the pose does not run every tick. After a check finds the
robot ``c`` metres from the nearest obstacle, no point of it can touch anything before
the increments have moved it that far; the travel per tick is bounded by
Σ |Δq| × lever (:meth:`~pymotoros.kinematics.collision.CollisionWorld.lever_arms`),
with each joint's lever arm at the last check (grown by the clearance), so the next
check is found by a binary search over the summed travel. Two links of one arm approach
each other at most twice as fast. Only ticks in contact are checked one by one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final, Protocol

import numpy as np
import numpy.typing as npt

from pymotoros.models.cell import CellModels
from pymotoros.models.travel import tick_travel_reaches
from pymotoros.models.workspace import ContactLike, ContactSpans
from pymotoros.motion import GroupAxes, to_pulses
from pymotoros.trajectory.files import Trajectory

F64Array = npt.NDArray[np.float64]


class CollisionModel(Protocol):
    """What the check needs of a collision model (the cell's robot and obstacles).

    :class:`pymotoros.kinematics.collision.CollisionWorld` is one; the caller (the CLI)
    builds it, so this layer depends on no kinematics library.
    """

    def probe(self, qs: Sequence[F64Array]) -> tuple[float, Sequence[ContactLike]]: ...
    def self_distances(self, qs: Sequence[F64Array]) -> Sequence[ContactLike]: ...
    def joint_reach(self, group_index: int) -> list[float]: ...
    def lever_arms(self, group_index: int) -> list[float]: ...
    def self_invariant_joints(self, group_index: int) -> tuple[int, ...]: ...
    def free_waypoints(
        self, waypoints: Sequence[Sequence[float]], *, time_limit_s: float | None = None
    ) -> list[list[float]]:
        """Collision-free joint waypoints through ``waypoints`` (``plan --avoid``'s search;
        :class:`~pymotoros.errors.PathBlockedError` naming the obstacle in the way)."""
        ...


MIN_STEP_M: Final = 1e-6
"""Clearance below this means "check the next tick" (contact, or grazing)."""


@dataclass(frozen=True, slots=True)
class Collision:
    """One contact along the motion: from ``time_s`` on, ``link`` touches ``obstacle``."""

    time_s: float
    obstacle: str
    """The obstacle's name; for a self-collision the other link."""
    link: str
    group: str
    depth_mm: float
    """The deepest overlap while the contact lasts."""
    self_collision: bool = False
    end_s: float = 0.0
    """When the contact ends (the motion's end if it does not)."""

    def to_json(self) -> dict[str, Any]:
        return {
            "time_s": round(self.time_s, 6),
            "end_s": round(self.end_s, 6),
            "obstacle": self.obstacle,
            "link": self.link,
            "group": self.group,
            "depth_mm": round(self.depth_mm, 3),
            "self_collision": self.self_collision,
        }

    def text(self) -> str:
        what = "itself" if self.self_collision else "obstacle"
        return (
            f"collision at {self.time_s:.3f} s: {self.group} {self.link} touches {what} "
            f"{self.obstacle!r} ({self.depth_mm:.1f} mm deep, until {self.end_s:.3f} s)"
        )


def joint_paths(
    traj: Trajectory,
    cell: CellModels,
    per_group: dict[str, tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]],
) -> tuple[F64Array, list[F64Array]]:
    """(time per tick in s, per cell group its joints per tick in rad) of a checked
    trajectory; a group the file does not move stands at its home."""
    columns = dict(traj.group_columns(cell.robot))
    ticks = max((len(t) for t, _ in per_group.values()), default=0)
    time_s = np.zeros(ticks)
    paths: list[F64Array] = []
    for gi, group in enumerate(cell.robot.groups):
        q = np.tile(np.asarray(group.home, dtype=float), (ticks + 1, 1))
        if group.name in per_group and gi in columns:
            axes = GroupAxes.from_model(group, cell.controller)
            time_ms, inc = per_group[group.name]
            pos0 = traj.positions[0, columns[gi]]
            start = np.array(axes.take(to_pulses(tuple(pos0.tolist()), axes)), dtype=np.int64)
            pulses = np.vstack([start, start + np.cumsum(inc, axis=0)])
            for col, ros in enumerate(axes.columns_list):
                q[: len(pulses), ros] = pulses[:, col] / float(axes.factors_ros[ros])
            q[len(pulses) :] = q[len(pulses) - 1]
            if len(time_ms) == ticks:
                time_s = np.asarray(time_ms, dtype=float) / 1000.0
        paths.append(q)
    return np.concatenate(([float(traj.times[0])], time_s)), paths


class _Travel:
    """How far any point of the robot can have moved since a tick (m): per tick, each
    group's |Δq| weighted by the lever arm of each joint at the last check."""

    def __init__(self, world: CollisionModel, paths: Sequence[F64Array]) -> None:
        self._world = world
        self._steps = [np.abs(np.diff(q, axis=0)) for q in paths]
        self._reach = [np.asarray(world.joint_reach(g), dtype=float) for g in range(len(paths))]
        self.ticks = len(paths[0])

    def next_check(self, k: int, step: float, *, for_self: bool) -> int:
        """The first tick after ``k`` at which the robot may have moved ``step`` metres
        (with the lever arms of the check just made at ``k``); ``for_self``: only the
        motion that can change a distance between two of its own links."""
        weights = []
        for g, reach in enumerate(self._reach):
            if len(reach):
                levers = np.asarray(self._world.lever_arms(g), dtype=float)
                w = np.minimum(reach, levers + step)
                if for_self:
                    w[list(self._world.self_invariant_joints(g))] = 0.0
                weights.append((g, w))
        steps = self._steps

        def travel(a: int, b: int) -> npt.NDArray[np.float64]:
            per_tick = np.zeros(b - a)
            for g, w in weights:
                per_tick += steps[g][a:b] @ w
            return per_tick

        return tick_travel_reaches(travel, k, self.ticks, step)


def find_collisions(
    traj: Trajectory,
    cell: CellModels,
    per_group: dict[str, tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]],
    world: CollisionModel,
) -> list[Collision]:
    """Every contact along the motion, in time order (see the module docstring);
    ``world`` holds the cell's robot groups (in cell order) and obstacles."""
    times, paths = joint_paths(traj, cell, per_group)
    travel = _Travel(world, paths)
    obstacle_spans, self_spans = ContactSpans(), ContactSpans()
    n = len(times)
    next_obstacle = next_self = 0
    while min(next_obstacle, next_self) < n:
        k = min(next_obstacle, next_self)
        qs = [p[k] for p in paths]
        now = float(times[k])
        if k == next_obstacle:
            clearance, contacts = world.probe(qs)
            obstacle_spans.update(contacts, now)
            next_obstacle = (
                k + 1
                if contacts or clearance <= MIN_STEP_M
                else travel.next_check(k, clearance, for_self=False)
            )
        if k == next_self:
            self_clearance, self_hits = _self_probe(world, qs)
            self_spans.update(self_hits, now)
            next_self = (
                k + 1
                if self_hits or self_clearance <= MIN_STEP_M
                else travel.next_check(k, self_clearance, for_self=True)
            )
    end = float(times[-1]) if n else 0.0
    done = [
        Collision(s.start_s, s.obstacle, s.link, s.group, s.depth_mm, s.self_collision, s.end_s)
        for spans in (obstacle_spans, self_spans)
        for s in spans.close_all(end)
    ]
    done.sort(key=lambda c: (c.time_s, c.group, c.link, c.obstacle))
    return done


def _self_probe(world: CollisionModel, qs: Sequence[F64Array]) -> tuple[float, list[ContactLike]]:
    distances = world.self_distances(qs)
    hits = [c for c in distances if c.distance_m <= 0.0]
    return min((c.distance_m for c in distances), default=np.inf), hits


__all__ = ["Collision", "CollisionModel", "ContactLike", "find_collisions", "joint_paths"]
