"""The words and numbers of the client's workspace guard (:meth:`Avoidance.check
<pymotoros.client.avoid.Avoidance.check>`): a planned move at every interpolation tick,
the refusal of a move that does not back out of a contact with the way out the client
found, and what a robot a contact stopped touches where it stands.

Pure functions of a collision world (:class:`~pymotoros.kinematics.collision.CollisionWorld`)
and the client's tool table; the rule itself (which move "only takes the robot away")
is :mod:`pymotoros.kinematics.sweep`'s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Final

from pymotoros.client.planning import JointTrajectory
from pymotoros.client.tools import ToolTable
from pymotoros.errors import KinematicsError, PymotorosError

if TYPE_CHECKING:  # numpy, Pinocchio and Coal load only for a cell with obstacles
    import numpy as np
    import numpy.typing as npt

    from pymotoros.kinematics.collision import CollisionWorld
    from pymotoros.kinematics.sweep import SweepResult, SweptContact
    from pymotoros.models.workspace import ContactLike

BACK_OUT_STEP_M: Final = 0.02
"""TCP step (20 mm) tried along each base axis to find the way out of a contact named in
a refusal: enough to clear a stop's overlap (a few mm), short enough to stay near."""
STOPPED_NEAR_M: Final = 0.005
"""A link this close to an obstacle where a collision alarm stopped the robot is named
as the contact (the twin and a real arm stop, or back off, within a few mm of it)."""
DEEPER_M: Final = 5e-5
"""How much deeper than at the start (0.05 mm) a refusal calls "the overlap grows"."""
FORCE_HINT: Final = "or give --force (force=True)"


def tick_positions(
    trajectory: JointTrajectory, period_s: float
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(times, positions) of ``trajectory`` at every interpolation tick (``period_s``)
    and at its end: the cubic MotoROS fits between two points (positions and
    velocities at both ends, :meth:`JointTrajectory.position_at`), vectorised."""
    import numpy as np

    pts = trajectory.points
    t_points = np.array([p.time for p in pts], dtype=float)
    pos = np.array([p.positions for p in pts], dtype=float)
    if len(pts) == 1:
        return t_points, pos
    vel = np.array([p.velocities for p in pts], dtype=float)
    times = np.arange(0.0, trajectory.duration, period_s)
    times = np.append(times, trajectory.duration)
    i = np.clip(np.searchsorted(t_points, times, side="right") - 1, 0, len(pts) - 2)
    h = (t_points[i + 1] - t_points[i])[:, None]
    s = np.clip((times[:, None] - t_points[i][:, None]) / np.where(h > 0, h, 1.0), 0.0, 1.0)
    h00 = 2 * s**3 - 3 * s**2 + 1
    h10 = s**3 - 2 * s**2 + s
    h01 = -2 * s**3 + 3 * s**2
    h11 = s**3 - s**2
    out = h00 * pos[i] + h10 * h * vel[i] + h01 * pos[i + 1] + h11 * h * vel[i + 1]
    return times, out


def start_contacts(found: SweepResult) -> list[SweptContact]:
    """The contacts the robot already had where the move starts (else the first)."""
    return [c for c in found.contacts if c.at_start] or found.contacts[:1]


def names(contacts: Sequence[SweptContact]) -> str:
    """``obstacle 'fixture' (R1 tool)`` for each contact, joined."""
    return ", ".join(f"obstacle {c.obstacle!r} ({c.group} {c.link})" for c in contacts)


def stuck_refusal(
    world: CollisionWorld,
    tools: ToolTable,
    found: SweepResult,
    start: npt.NDArray[np.float64],
    columns: Sequence[int],
    moves_tools: Mapping[int, int] | None = None,
) -> str:
    """The refusal of a move that starts in contact and goes deeper: what it touches,
    how deep it would go, and how to back out."""
    touching = start_contacts(found)
    start_mm = -found.start_clearance_m * 1000.0
    end_mm = -found.deepest_m * 1000.0
    step = found.worse
    if step is not None and step.start_mm is None:
        worse = (
            f"{step.group} {step.link} touches obstacle {step.obstacle!r} at {step.time_s:.3f} s "
            f"({step.depth_mm:.1f} mm deep)"
        )
    elif (
        step is not None
        and step.start_mm is not None
        and step.start_mm < start_mm - DEEPER_M * 1000.0
    ):
        # a contact shallower than the deepest one goes deeper: name it
        worse = (
            f"{step.group} {step.link} goes deeper into obstacle {step.obstacle!r}: "
            f"{step.start_mm:.1f} mm at the start, {step.depth_mm:.1f} mm at {step.time_s:.3f} s"
        )
    elif found.deepest_m < found.start_clearance_m - DEEPER_M:
        worse = f"the overlap grows to {end_mm:.1f} mm at {found.deepest_s:.3f} s"
    elif found.deepest_m <= 0.0 and math.isfinite(found.deepest_m):
        worse = f"it stays {start_mm:.1f} mm deep, sliding along it"
    else:
        worse = "it touches again later"
    hint = back_out_hint(world, tools, start, columns, moves_tools)
    return (
        f"the robot starts touching {names(touching)} ({start_mm:.1f} mm deep) and this "
        f"move does not take it away ({worse}); nothing was sent. A move along which the "
        f"clearance only grows is allowed: back out first{hint}, or move with --avoid "
        f"(avoid=True), which leaves the contact before it searches, {FORCE_HINT}"
    )


def back_out_hint(
    world: CollisionWorld,
    tools: ToolTable,
    start: npt.NDArray[np.float64],
    columns: Sequence[int],
    moves_tools: Mapping[int, int] | None = None,
) -> str:
    """``, e.g. dz=+0.020 m (...)``: the TCP step along a base axis that gains the
    most clearance from where the robot stands ("" when none does, or no IK), with the
    TCP of the move's tool (``moves_tools``: group index -> tool number), else the one in
    force; the command it prints names that tool (``--tool``), so the step runs guarded
    with the same shape on the flange."""
    import numpy as np

    from pymotoros.kinematics import pose_to_matrix
    from pymotoros.kinematics.path_search import split

    if not columns:
        return ""
    g = group_of(world, columns[0])
    qs = split(start, world.joint_counts)
    here, _ = world.probe(qs)
    best: tuple[float, str, str] | None = None  # (clearance, "dz", "+0.020")
    number = (moves_tools or {}).get(g)
    try:
        number = tools.in_force(g) if number is None else number
        chain = tools.chain(g, number)
    except PymotorosError:
        return ""
    pose = chain.fk(qs[g])
    for axis, key in enumerate(("dx", "dy", "dz")):
        for sign in (1.0, -1.0):
            step = np.zeros(6)
            step[axis] = sign * BACK_OUT_STEP_M
            target = pose.copy()
            target[:3, 3] = pose[:3, 3] + pose_to_matrix(step.tolist())[:3, 3]
            try:
                q = chain.ik(target, qs[g]).q
            except KinematicsError:
                continue
            moved = [*qs]
            moved[g] = np.asarray(q, dtype=float)
            clearance, _ = world.probe(moved)
            if clearance > here and (best is None or clearance > best[0]):
                best = (clearance, key, f"{sign * BACK_OUT_STEP_M:+.3f}")
    if best is None:
        return ""
    _, key, value = best
    relative = f"{key}={value.lstrip('+')}"
    tool = "" if moves_tools is None or g not in moves_tools else f", tool={number}"
    return (
        f", e.g. {key} {value} m (`pymotoros move --relative {relative} --tool {number}` with "
        f"this cell's --config, move_relative({relative}{tool}))"
    )


def group_of(world: CollisionWorld, column: int) -> int:
    at = 0
    for g, n in enumerate(world.joint_counts):
        if column < at + n:
            return g
        at += n
    return 0


def contact_words(world: CollisionWorld, qs: Sequence[npt.NDArray[np.float64]]) -> str | None:
    """What the robot touches at ``qs`` (per group), or nearly (:data:`STOPPED_NEAR_M`),
    in words with the distance in mm; None when nothing is that near."""
    clearance, contacts = world.probe(qs)
    if contacts:
        c: ContactLike = min(contacts, key=lambda c: c.distance_m)
        return (
            f"{c.group} {c.link} touches obstacle {c.obstacle!r} "
            f"({-c.distance_m * 1000.0:.1f} mm deep)"
        )
    if clearance > STOPPED_NEAR_M:
        return None
    nearest = world.nearest(qs)
    if nearest is None:
        return None
    return (
        f"{nearest.group} {nearest.link} stands {nearest.distance_m * 1000.0:.1f} mm from "
        f"obstacle {nearest.obstacle!r}"
    )


__all__ = [
    "BACK_OUT_STEP_M",
    "FORCE_HINT",
    "STOPPED_NEAR_M",
    "back_out_hint",
    "contact_words",
    "group_of",
    "names",
    "start_contacts",
    "stuck_refusal",
    "tick_positions",
]
