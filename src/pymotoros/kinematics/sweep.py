"""Every contact along a sampled joint motion: the check that guards each move of the client.

The client plans a move (joint, pose, straight line, around obstacles) as trajectory
points; MotoROS turns them into one increment per interpolation tick (a cubic between
points). :func:`sweep` takes the positions at those ticks (every joint of every group of
a :class:`~pymotoros.kinematics.collision.CollisionWorld`) and finds every contact with
an obstacle or between two links of one arm, each reported once with the time it
starts, the link, the obstacle, the deepest overlap and when it ends: the same record
``pymotoros check --config`` prints for a file.

Cost: a full check of the pose does not run every tick. After a check finds the robot
``c`` metres from the nearest obstacle, no point of it can touch anything before the
robot has moved that far, and one tick moves any point at most Σ |Δq| × reach
(:meth:`CollisionWorld.joint_reach`, the farthest point each joint moves in any pose):
the next check is found by a binary search over that summed travel. Two links of one
arm approach each other at most twice as fast. Ticks in contact are checked one by one.

A robot that starts touching an obstacle (stopped by a contact) must be able to leave
it. :attr:`SweepResult.receding` says whether the move only takes it away, judged for
each contact it starts in (a link and an obstacle) on its own, at every tick while the
robot is in contact: the signed distance of that link to that obstacle (negative: the
depth of the overlap) never falls more than :data:`RECEDE_TOLERANCE_M` below the largest
it has had since the start, and no other contact begins (nor one that has ended begins
again); a move that ends still in contact must have taken at least one of its contacts
away by more than that tolerance (sliding along an obstacle at the same depth does not
take the robot away). One shallow contact may not go deeper because a deeper one
recedes: each is judged by itself. docs/workspace.md, "Backing out of a contact".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final, Protocol

import numpy as np
import numpy.typing as npt

from pymotoros.models.travel import tick_travel_reaches
from pymotoros.models.workspace import ContactLike, ContactSpans

F64Array = npt.NDArray[np.float64]

MIN_STEP_M: Final = 1e-6
"""Clearance below this means "check the next tick" (contact, or grazing)."""
RECEDE_TOLERANCE_M: Final = 1e-5
"""How much the smallest distance may fall below its largest since the start and still
count as "not going deeper" (0.01 mm: the distance solver's rounding, far below one pulse of
travel at the arm's tip)."""


class SweepWorld(Protocol):
    """What the sweep needs of a collision model (a :class:`CollisionWorld` is one)."""

    def probe(self, qs: Sequence[F64Array]) -> tuple[float, Sequence[ContactLike]]: ...
    def self_distances(self, qs: Sequence[F64Array]) -> Sequence[ContactLike]: ...
    def joint_reach(self, group_index: int) -> list[float]: ...
    def lever_arms(self, group_index: int) -> list[float]: ...


@dataclass(frozen=True, slots=True)
class SweptContact:
    """One contact along the motion: from ``time_s`` to ``end_s``, ``link`` touches
    ``obstacle`` (for a self-collision: the other link), at most ``depth_mm`` deep."""

    time_s: float
    obstacle: str
    link: str
    group: str
    depth_mm: float
    self_collision: bool = False
    end_s: float = 0.0
    at_start: bool = False
    """The robot already touched it where the move starts."""

    def text(self) -> str:
        what = "itself" if self.self_collision else "obstacle"
        return (
            f"collision at {self.time_s:.3f} s: {self.group} {self.link} touches {what} "
            f"{self.obstacle!r} ({self.depth_mm:.1f} mm deep, until {self.end_s:.3f} s)"
        )


@dataclass(frozen=True, slots=True)
class Worsening:
    """A contact that goes deeper during a back-out (``start_mm`` -> ``depth_mm`` deep at
    ``time_s``), or a new one (``start_mm`` is None: not touching where the move starts)."""

    time_s: float
    group: str
    link: str
    obstacle: str
    start_mm: float | None
    depth_mm: float


@dataclass(slots=True)
class SweepResult:
    """What :func:`sweep` found along the motion."""

    contacts: list[SweptContact] = field(default_factory=list)
    """Every contact, in time order (those already there at the start included)."""
    start_clearance_m: float = math.inf
    """Smallest signed distance to the obstacles at the start (negative: in contact)."""
    receding: bool = True
    """The robot starts in contact and only moves out of it (see the module docstring);
    True too when it starts clear."""
    deepest_m: float = math.inf
    """While it starts in contact: the smallest signed distance reached after the start."""
    deepest_s: float = 0.0
    """When that was."""
    worse: Worsening | None = None
    """While it starts in contact: the first contact that makes the move not receding
    (one going deeper, or a new one); None when it recedes or only slides."""

    @property
    def starts_in_contact(self) -> bool:
        return self.start_clearance_m <= 0.0

    @property
    def blocking(self) -> list[SweptContact]:
        """The contacts that refuse the move: all of them, unless it starts in contact
        and only backs out (then none)."""
        if self.starts_in_contact and self.receding:
            return [c for c in self.contacts if not c.at_start]
        return self.contacts


def _split(q: F64Array, sizes: Sequence[int]) -> list[F64Array]:
    out, at = [], 0
    for n in sizes:
        out.append(q[at : at + n])
        at += n
    return out


def sweep(
    world: SweepWorld, times: F64Array, positions: F64Array, sizes: Sequence[int]
) -> SweepResult:
    """Every contact of the robot at ``positions`` (ticks × every joint of every group of
    ``world``, ``sizes`` joints per group) sampled at ``times`` (s)."""
    ticks = len(times)
    result = SweepResult()
    if ticks == 0:
        return result
    travel = _Travel(world, positions, sizes)
    spans = ContactSpans()
    next_obstacle = next_self = 0
    backing = _BackOut()
    while min(next_obstacle, next_self) < ticks:
        k = min(next_obstacle, next_self)
        qs = _split(positions[k], sizes)
        now = float(times[k])
        seen: list[ContactLike] = []
        if k == next_obstacle:
            clearance, contacts = world.probe(qs)
            seen.extend(contacts)
            if k == 0:
                result.start_clearance_m = clearance
            backing.follow(result, k, now, clearance, contacts)
            next_obstacle = travel.next_check(k, clearance, contacts)
        else:  # the obstacles were not due: keep what is open against them
            seen.extend(_kept(spans, self_collision=False))
        if k == next_self:
            distances = world.self_distances(qs)
            hits = [c for c in distances if c.distance_m <= 0.0]
            seen.extend(hits)
            own = min((c.distance_m for c in distances), default=math.inf) / 2.0
            next_self = travel.next_check(k, own, hits)
        else:
            seen.extend(_kept(spans, self_collision=True))
        spans.update(seen, now, at_start=k == 0)
    if result.starts_in_contact and not backing.came_out():
        result.receding = False  # still in every contact at the end, none shallower
    done = [
        SweptContact(
            s.start_s, s.obstacle, s.link, s.group, s.depth_mm, s.self_collision, s.end_s,
            s.at_start,
        )
        for s in spans.close_all(float(times[-1]))
    ]  # fmt: skip
    done.sort(key=lambda c: (c.time_s, c.group, c.link, c.obstacle))
    result.contacts = done
    return result


class _Kept:
    """A contact carried over a tick at which its kind was not checked."""

    __slots__ = ("distance_m", "group", "link", "obstacle", "self_collision")

    def __init__(self, key: tuple[str, str, str], depth_mm: float, is_self: bool) -> None:
        self.group, self.link, self.obstacle = key
        self.distance_m = -depth_mm / 1000.0
        self.self_collision = is_self


def _kept(spans: ContactSpans, *, self_collision: bool) -> list[ContactLike]:
    """The open contacts of one kind, carried over a tick at which it was not checked."""
    return [
        _Kept(key, span.depth_mm, self_collision)
        for key, span in spans.open.items()
        if span.self_collision == self_collision
    ]


class _Travel:
    """How far any point of the robot can have moved since a tick (m): per tick, each
    joint's |Δq| times its lever arm at the last check grown by the clearance (a lever
    grows by at most the distance moved), never more than its reach in any pose."""

    def __init__(self, world: SweepWorld, positions: F64Array, sizes: Sequence[int]) -> None:
        self._world = world
        self._sizes = tuple(sizes)
        self._steps = np.abs(np.diff(positions, axis=0))
        self._reach = np.concatenate(
            [
                np.asarray(world.joint_reach(g) or [0.0] * n, dtype=float)  # no shapes: 0
                for g, n in enumerate(sizes)
            ]
        )
        self.ticks = len(positions)

    def _weights(self, step: float) -> F64Array:
        levers = np.concatenate(
            [
                np.asarray(self._world.lever_arms(g) or [0.0] * n, dtype=float)
                for g, n in enumerate(self._sizes)
            ]
        )
        weights: F64Array = np.minimum(self._reach, levers + step)
        return weights

    def next_check(self, k: int, clearance: float, hits: Sequence[ContactLike]) -> int:
        """The next tick at which a check is due after one at ``k`` found ``clearance``
        (the levers of that check: the world was just placed at tick ``k``)."""
        if hits or clearance <= MIN_STEP_M:
            return k + 1
        if not math.isfinite(clearance):
            return self.ticks
        weights = self._weights(clearance)
        steps = self._steps
        return tick_travel_reaches(lambda a, b: steps[a:b] @ weights, k, self.ticks, clearance)


class _BackOut:
    """The receding rule for a robot that starts in contact (module docstring), per
    contact: (group, link, obstacle) -> its signed distance at the start, the largest
    since, and the latest; a contact that has ended is dropped (it may not come back)."""

    def __init__(self) -> None:
        self.start: dict[tuple[str, str, str], float] = {}
        self.best: dict[tuple[str, str, str], float] = {}
        self.last: dict[tuple[str, str, str], float] = {}

    def follow(
        self,
        result: SweepResult,
        k: int,
        now: float,
        clearance: float,
        contacts: Sequence[ContactLike],
    ) -> None:
        touching = {(c.group, c.link, c.obstacle): c.distance_m for c in contacts}
        touching = {key: d for key, d in touching.items() if d <= 0.0}
        if k == 0:
            self.start, self.best, self.last = dict(touching), dict(touching), dict(touching)
            return
        if result.start_clearance_m > 0.0:
            return
        if clearance < result.deepest_m:
            result.deepest_m, result.deepest_s = clearance, now
        for key in [key for key in self.last if key not in touching]:
            del self.last[key]  # out of it: were it to come back, it would be a new one
        for key, d in touching.items():
            best = self.best.get(key) if key in self.last else None
            if best is not None and d >= best - RECEDE_TOLERANCE_M:
                self.best[key] = max(best, d)
                self.last[key] = d
                continue
            if result.receding:
                start = self.start.get(key) if best is not None else None
                result.receding = False
                result.worse = Worsening(
                    now, *key, None if start is None else -start * 1000.0, -d * 1000.0
                )

    def came_out(self) -> bool:
        """At least one contact has ended, or is shallower than at the start by more
        than the tolerance."""
        return any(
            key not in self.last or self.last[key] > d + RECEDE_TOLERANCE_M
            for key, d in self.start.items()
        )


__all__ = [
    "RECEDE_TOLERANCE_M",
    "SweepResult",
    "SweepWorld",
    "SweptContact",
    "Worsening",
    "sweep",
]
