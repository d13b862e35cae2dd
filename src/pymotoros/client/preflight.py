"""The client's pre-flight: MotoROS's own point checks, run on the PC before sending.

Nothing here re-derives a rule: the start tolerance, the float32 speed limit, the
pulse conversion of each float mode and the interleaved sequence-0 checks are the
functions of :mod:`pymotoros.models.rules`, the very ones the virtual controller
applies (reference §3.4, §5.5, §5.7). The client knows the robot model, the
controller model (period, float mode) and the latest feedback; settled feedback gives
back the commanded pulses MotoROS compares a start with (:func:`feedback_pulses`).

* :func:`first_refusal`: what MotoROS would answer to a point (subcode, group, axis).
* :func:`start_deviations` / :func:`speed_deviations`: every axis beyond a limit, as
  :class:`AxisDeviation` values for the typed errors.
* :func:`speed_screen` / :func:`within_screen`: the speed check's limits once per
  trajectory, so a point well within them costs one pass instead of the full check.
"""

from __future__ import annotations

import operator
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from pymotoros.client.errors import AxisDeviation
from pymotoros.client.planning import TrajectoryPoint
from pymotoros.models import ControllerModel, GroupModel
from pymotoros.models.rules import (
    GroupRules,
    Refusal,
    TrajPoint,
    check_axis_speed,
    check_speed,
    check_start,
    f32,
    feedback_pulses,
    group_rules,
    start_deviation,
    to_pulses,
)
from pymotoros.protocol.constants import INT32_MAX


@dataclass(frozen=True, slots=True)
class PreflightRefusal:
    """The refusal MotoROS would send for a point, and where in the joined joints it is."""

    group: int
    """Index into the ``models`` given (the order of the joined joints)."""
    refusal: Refusal
    """Subcode, the index MotoROS's loop was at (controller slot for 3011, ROS index for
    3013, within the group), the numbers and the sentence."""


def _split(values: Sequence[float], models: Sequence[GroupModel]) -> list[tuple[float, ...]]:
    out, i = [], 0
    for m in models:
        out.append(tuple(values[i : i + m.num_axes]))
        i += m.num_axes
    return out


def first_refusal(
    point: TrajectoryPoint,
    sequence: int,
    models: Sequence[GroupModel],
    controller: ControllerModel,
    current: Sequence[float] | None = None,
) -> PreflightRefusal | None:
    """The first refusal MotoROS makes for ``point`` (3011 or 3013), or None if it accepts.

    Groups are checked in order, as MotoROS walks a JOINT_TRAJ_PT_FULL_EX. For sequence 0
    ``current`` (the settled feedback, joints of ``models`` joined) gives the commanded
    position; without it only the speed part of the interleaved check runs.
    """
    positions = _split(point.positions, models)
    velocities = _split(point.velocities, models)
    joined = _split(current, models) if current is not None else [None] * len(models)
    for g, (model, pos, vel, cur) in enumerate(
        zip(models, positions, velocities, joined, strict=True)
    ):
        rules = group_rules(model, controller)
        traj = TrajPoint(point.time, pos, vel)
        if sequence == 0:
            commanded = to_pulses(pos, rules) if cur is None else feedback_pulses(cur, rules)
            refusal = check_start(traj, commanded, rules)
        else:
            refusal = check_speed(traj, rules)
        if refusal is not None:
            return PreflightRefusal(g, refusal)
    return None


def start_deviations(
    point: TrajectoryPoint,
    models: Sequence[GroupModel],
    current: Sequence[float] | None,
    controller: ControllerModel,
) -> list[AxisDeviation]:
    """Axes of ``point`` beyond the start tolerance from ``current`` (MotoROS's pulses)."""
    if current is None:
        return []
    out = []
    base = 0
    for model, want, have in zip(
        models, _split(point.positions, models), _split(current, models), strict=True
    ):
        rules = group_rules(model, controller)
        requested = to_pulses(want, rules)
        commanded = feedback_pulses(have, rules)
        for i, (w, h) in enumerate(zip(want, have, strict=False)):
            slot = rules.ros_to_slot[i]
            pulses = start_deviation(requested[slot], commanded[slot])
            if pulses is not None:
                out.append(AxisDeviation(base + i, model.axes[i].name, w, h, pulses))
        base += model.num_axes
    return out


def speed_deviations(
    point: TrajectoryPoint, models: Sequence[GroupModel], controller: ControllerModel
) -> list[AxisDeviation]:
    """Axes of ``point`` whose velocity MotoROS's speed check refuses (§5.5)."""
    out = []
    base = 0
    for model, vel in zip(models, _split(point.velocities, models), strict=True):
        rules = group_rules(model, controller)
        for i, v in enumerate(vel):
            if _refused_speed(i, v, rules):
                out.append(AxisDeviation(base + i, model.axes[i].name, v, rules.max_speed[i]))
        base += model.num_axes
    return out


_NUMBER_TYPES: Final = frozenset((float, int))


def speed_screen(models: Sequence[GroupModel], controller: ControllerModel) -> tuple[float, ...]:
    """Per joint of ``models`` joined, a speed under which MotoROS's check surely passes.

    The largest float32 at or below the axis's limit: for ``|v|`` at or under it, the
    float32 the wire carries is too (rounding to float32 is monotonic and keeps float32
    values), so :func:`speed_deviations` would find nothing and log nothing. Computed
    once per trajectory; :func:`within_screen` is then one pass per point instead of
    the rules looked up and every velocity rounded. A limit that is not a finite
    speed gives -1.0: nothing passes the screen, the full check runs.
    """
    out: list[float] = []
    for model in models:
        rules = group_rules(model, controller)
        out.extend(_f32_at_most(rules.max_speed[i]) for i in range(model.num_axes))
    return tuple(out)


def within_screen(velocities: Sequence[float], screen: Sequence[float]) -> bool:
    """True when every velocity is a plain number within ``screen`` (see :func:`speed_screen`);
    False means "run :func:`speed_deviations`", not "refused" (NaN and inf land here)."""
    return _NUMBER_TYPES.issuperset(map(type, velocities)) and all(
        map(operator.le, map(abs, velocities), screen)
    )


def _f32_at_most(limit: float) -> float:
    """The largest float32 value ≤ ``limit`` (``limit`` finite, ≥ 0), else -1.0."""
    if not 0.0 <= limit < INT32_MAX:
        return -1.0
    nearest = f32(limit)
    if nearest <= limit:
        return nearest
    (bits,) = _F32_BITS.unpack(_F32.pack(nearest))
    (below,) = _F32.unpack(_F32_BITS.pack(bits - 1))  # positive: one ulp down
    return float(below)


_F32: Final = struct.Struct("<f")
_F32_BITS: Final = struct.Struct("<I")


def _refused_speed(i: int, v: float, rules: GroupRules) -> bool:
    """MotoROS's test on the float32 the wire carries."""
    return check_axis_speed(i, f32(v), rules) is not None
