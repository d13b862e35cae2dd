"""The point checks MotoROS makes before it accepts a trajectory point (§3.4, §5.5).

Shared by the virtual controller, ``pymotoros interpolate`` and anyone who wants a
pre-flight check. A refused point gives a :class:`Refusal` value (never an
exception): the subcode MotoROS sends, the axis its loop was at, the numbers and a
sentence that explains them.

Two behaviours of the real code are kept on purpose:

* **Interleaving.** For a trajectory start (sequence 0) MotoROS walks the 8 slots once
  and, at each index, tests the start position (controller slot i) and then the speed
  (ROS index i). The first failing index decides whether 3011 or 3013 is sent.
* **Truncated speed check.** The velocity goes through C's integer ``abs()``, so the
  test is ``trunc(|v|) > limit``: with a 2.27 rad/s limit, 2.9 rad/s passes and
  3.0 rad/s is refused. The checks log a warning whenever this lets a velocity above
  the limit through.

One deviation, for safety: a velocity that is not finite or does not fit an int32
(where C's conversion is undefined) is refused with 3013.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

from pymotoros.errors import TrajectoryRejectedError
from pymotoros.motion.axes import GroupAxes, to_pulses
from pymotoros.motion.constants import (
    INT32_MAX,
    MAX_POINT_TIME_S,
    SLOTS,
    START_TOLERANCE_PULSES,
)
from pymotoros.motion.numerics import f32
from pymotoros.motion.points import TrajPoint
from pymotoros.protocol.constants import InvalidSubcode

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class Refusal:
    """Why MotoROS refuses a point: what goes on the wire, and the numbers behind it."""

    subcode: InvalidSubcode
    axis: int | None
    """The index MotoROS's loop was at: a controller slot for 3011, a ROS index for
    3013; None for a check that is not per axis (3016)."""
    joint: str
    """Name of the joint at that index ("unused slot 7" past the last axis)."""
    value: float
    """3011: |requested − commanded| in pulses; 3013: |velocity| in rad/s;
    3016: the time in s."""
    limit: float
    """3011: 30 pulses; 3013: the axis maximum in rad/s; 3016: 14400 s."""
    message: str
    """One sentence with the numbers, for logs and error messages."""

    def error(self, point: int) -> TrajectoryRejectedError:
        """This refusal as the exception the offline engine raises for point ``point``."""
        return TrajectoryRejectedError(
            f"point {point}: {self.message}",
            point=point,
            subcode=int(self.subcode),
            axis=self.axis,
            value=self.value,
            limit=self.limit,
        )


def check_time(point: TrajPoint) -> Refusal | None:
    """JOINT_TRAJ_PT_FULL's 4-hour check: time ≥ 14400 s → 3016 (§3.4; not on FULL_EX)."""
    t = f32(point.time)
    if t >= MAX_POINT_TIME_S or math.isnan(t):
        return Refusal(
            InvalidSubcode.DATA_TIME,
            None,
            "",
            t,
            MAX_POINT_TIME_S,
            f"time {t:g} s is at or beyond the {MAX_POINT_TIME_S:g} s (4 h) MotoROS accepts "
            f"({_code(InvalidSubcode.DATA_TIME)})",
        )
    return None


def check_start(
    point: TrajPoint, commanded_pulses: Sequence[int], axes: GroupAxes
) -> Refusal | None:
    """The sequence-0 checks (§3.4 step 5.3): start position and speed, interleaved.

    ``commanded_pulses`` is the group's commanded position (8 slots, controller order);
    MotoROS compares with it, not with the feedback. All 8 slots are tested, so a
    velocity of 1 rad/s or more in a slot past the last axis is refused.
    """
    requested = to_pulses(point.pos, axes)
    vel = _velocities(point)
    for i in range(SLOTS):
        diff = abs(requested[i] - commanded_pulses[i])
        if diff > START_TOLERANCE_PULSES:
            return _start_refusal(i, requested[i], commanded_pulses[i], diff, axes)
        refusal = _speed(i, vel[i], axes)
        if refusal is not None:
            return refusal
    return None


def check_speed(point: TrajPoint, axes: GroupAxes) -> Refusal | None:
    """The sequence > 0 speed check (§3.4 step 6.2): ROS indices below the axis count."""
    vel = _velocities(point)
    for i in range(axes.num_axes):
        refusal = _speed(i, vel[i], axes)
        if refusal is not None:
            return refusal
    return None


def _velocities(point: TrajPoint) -> list[float]:
    return [f32(v) for v in point.vel] + [0.0] * (SLOTS - len(point.vel))


def _code(subcode: InvalidSubcode) -> str:
    return f"{int(subcode)} {subcode.name}"


def _start_refusal(
    slot: int, requested: int, commanded: int, diff: int, axes: GroupAxes
) -> Refusal:
    factor = axes.pulses_per_unit[slot]
    joint = axes.joint_at_slot(slot)
    message = (
        f"{joint} (controller slot {slot}): the start point is {requested} pulses "
        f"({requested / factor:.6g} rad) but the commanded position is {commanded} pulses "
        f"({commanded / factor:.6g} rad), {diff} pulses ({diff / factor:.3g} rad) apart; "
        f"MotoROS allows {START_TOLERANCE_PULSES} pulses "
        f"({_code(InvalidSubcode.DATA_START_POS)}). Start the trajectory where the robot is."
    )
    return Refusal(
        InvalidSubcode.DATA_START_POS,
        slot,
        joint,
        float(diff),
        float(START_TOLERANCE_PULSES),
        message,
    )


def _speed(i: int, v: float, axes: GroupAxes) -> Refusal | None:
    limit = axes.max_speed[i]
    speed = abs(v)
    if not speed <= INT32_MAX:  # NaN, inf, or beyond C's int conversion: refuse (safe)
        return _speed_refusal(i, speed, None, axes)
    whole = int(speed)  # C: abs((int)v), i.e. the velocity truncated toward zero
    if whole > limit:
        return _speed_refusal(i, speed, whole, axes)
    if speed > limit:
        logger.warning(
            "%s velocity %.6g rad/s is above the axis maximum %.6g rad/s, but MotoROS "
            "accepts it: its speed check truncates |v| to %d before comparing",
            axes.joint_name(i),
            speed,
            limit,
            whole,
        )
    return None


def _speed_refusal(i: int, speed: float, whole: int | None, axes: GroupAxes) -> Refusal:
    limit = axes.max_speed[i]
    joint = axes.joint_name(i)
    if i < axes.num_axes:
        slot = axes.ros_to_slot[i]
        where = (
            f"the axis maximum {limit:.6g} rad/s ({axes.max_speed_pulses[slot]} pulses/s, "
            f"{axes.max_increment[slot]} pulses per {axes.period_ms} ms tick)"
        )
        per_second = f" = {speed * axes.pulses_per_unit[slot]:.0f} pulses/s"
    else:
        where = "0 rad/s (no axis in this slot)"
        per_second = ""
    if whole is None:
        how = "it is not a number MotoROS's integer comparison can hold; refused for safety"
    else:
        how = (
            f"MotoROS truncates |v| to {whole} before comparing ({whole} > {limit:.6g}), "
            f"so any speed below {math.floor(limit) + 1} rad/s would have passed"
        )
    message = (
        f"{joint} (ROS index {i}): velocity {speed:.6g} rad/s{per_second} is above {where}; "
        f"{how} ({_code(InvalidSubcode.DATA_SPEED)})"
    )
    return Refusal(InvalidSubcode.DATA_SPEED, i, joint, speed, limit, message)
