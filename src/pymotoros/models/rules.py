"""MotoROS's point rules, numpy-free: the one home the controller and the client share.

The virtual controller (through the motion engine), ``pymotoros interpolate`` and the
client's pre-flight all decide with the functions here, so a point the client lets
through is a point the controller accepts, to the bit (reference §3.4, §5.5, §5.7, §11).

* :class:`GroupRules` – what MotoROS derives for one group: pulse ratios, maxInc,
  the speed limit in pulses/s and in rad/s (float32), the ROS-index → slot map.
  ``motion.GroupAxes`` extends it with the numpy arrays of the vectorised engine.
* :func:`to_pulses` (ConvertToMotoPos) and :func:`from_pulse` (ConvertToRosPos), in
  both float modes; :func:`feedback_pulses` recovers the pulses a reported position
  came from.
* :func:`check_time`, :func:`check_start`, :func:`check_speed` → :class:`Refusal`.

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

import functools
import logging
import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Final, Self

from pymotoros.errors import ConfigError, TrajectoryRejectedError
from pymotoros.models.controllers import ControllerModel, FloatMode
from pymotoros.models.robots import AxisModel, GroupModel
from pymotoros.protocol.constants import INT32_MAX, INT32_MIN, MAX_PULSE_AXES, InvalidSubcode

logger = logging.getLogger(__name__)

SLOTS: Final = MAX_PULSE_AXES
"""Axis slots of a control group: every pulse array and point array has 8 (§1.4, §5.7)."""

START_TOLERANCE_PULSES: Final = 30
"""Largest |requested − commanded| pulse difference a trajectory start may have (§3.4, §5.1)."""

MAX_POINT_TIME_S: Final = 14400.0
"""JOINT_TRAJ_PT_FULL refuses a point time at or beyond 4 h with 3016 (§3.4)."""

INVALID_AXIS_FACTOR: Final = 1.0
"""Pulse ratio MotoROS uses for a slot with no axis (§5.7, the default branch)."""

# --------------------------------------------------------------------------- float32 and C ints

_F32: Final = struct.Struct("<f")
_INT32_LOW: Final = float(INT32_MIN) - 1.0
_INT32_HIGH: Final = float(INT32_MAX) + 1.0

_X87_MANTISSA_BITS: Final = 64
"""Significand of the x87 extended format the x86 builds compute in (§11)."""
_F32_MANTISSA_BITS: Final = 24
_F32_MIN_EXPONENT: Final = -149
"""Exponent of float32's smallest subnormal (2⁻¹⁴⁹): the finest quantum it has."""
_F32_MAX: Final = 3.4028234663852886e38


def f32(value: float) -> float:
    """``value`` rounded to float32 (as a Python float). Overflow gives ±inf, as on the wire."""
    try:
        return float(_F32.unpack(_F32.pack(value))[0])
    except OverflowError:
        return math.copysign(math.inf, value)


def c_int(value: float, mode: FloatMode) -> int:
    """C's ``(int)value``: truncation toward zero.

    Out of the int32 range (or NaN) C leaves the result undefined; the x87 store gives
    the "integer indefinite" value INT32_MIN, the PowerPC conversion saturates (NaN
    gives 0). That is what the two builds' instructions do, not something the
    reference states; it only matters for absurd inputs.
    """
    if _INT32_LOW < value < _INT32_HIGH:
        return int(value)
    if mode is FloatMode.X87_EXTENDED or math.isnan(value):
        return INT32_MIN if mode is FloatMode.X87_EXTENDED else 0
    return INT32_MAX if value > 0 else INT32_MIN


def pulse(value: float, factor: float, mode: FloatMode) -> int:
    """``(int)(value * factor)`` for one float32 value and float32 pulse ratio (§5.7, §11).

    The float64 product of two float32 values is exact (48 significant bits), which is
    what the x87 truncates; FS100 rounds the product to float32 first.
    """
    product = value * factor
    if mode is FloatMode.STRICT_SINGLE:
        product = f32(product)
    return c_int(product, mode)


def _round_bits(x: Fraction, bits: int, min_exponent: int | None = None) -> Fraction:
    """``x`` rounded to ``bits`` significant bits, ties to even (and to a multiple of
    2^``min_exponent`` at most, for float32's subnormals)."""
    if x == 0:
        return x
    sign = -1 if x < 0 else 1
    a = abs(x)
    exponent = a.numerator.bit_length() - a.denominator.bit_length()
    if Fraction(2) ** exponent > a:
        exponent -= 1
    quantum_exp = exponent - bits + 1  # a lies in [2^e, 2^(e+1)): ulp is 2^(e − bits + 1)
    if min_exponent is not None:
        quantum_exp = max(quantum_exp, min_exponent)
    scaled = a / Fraction(2) ** quantum_exp
    whole = scaled.numerator // scaled.denominator
    rest = scaled - whole
    if rest > Fraction(1, 2) or (rest == Fraction(1, 2) and whole % 2 == 1):
        whole += 1
    return sign * whole * Fraction(2) ** quantum_exp


def from_pulse(count: int, factor: float, mode: FloatMode) -> float:
    """ConvertToRosPos: ``pulse / factor`` stored as float32 (§5.7, §11).

    x87: the quotient rounded to the 64-bit extended significand, then stored as
    float32 (two roundings, computed exactly here). FS100: the pulse count converted to
    float32, then a float32 division; the float64 quotient of two float32 values rounds
    to the same float32 as a correctly rounded single division (53 ≥ 2 × 24 + 2).
    """
    if mode is FloatMode.STRICT_SINGLE:
        return f32(f32(float(count)) / factor)
    if not (math.isfinite(factor) and factor > 0.0):
        raise ValueError(f"a pulse ratio is a positive float32 number, not {factor!r}")
    extended = _round_bits(Fraction(count) / Fraction(factor), _X87_MANTISSA_BITS)
    stored = _round_bits(extended, _F32_MANTISSA_BITS, _F32_MIN_EXPONENT)
    if abs(stored) > _F32_MAX:
        return math.copysign(math.inf, stored)
    return float(stored)


# --------------------------------------------------------------------------- points


@dataclass(frozen=True, slots=True)
class TrajPoint:
    """One trajectory point for one group, ROS order, up to 8 axes.

    Missing trailing slots count as 0.0, as the unused slots of a wire message do.
    """

    time: float
    """Seconds since the trajectory start (the point's ``time`` field)."""
    pos: tuple[float, ...]
    """Positions, rad (m for linear axes), ROS order."""
    vel: tuple[float, ...]
    """Velocities, rad/s (m/s), ROS order."""

    def __post_init__(self) -> None:
        if len(self.pos) > SLOTS or len(self.vel) > SLOTS:
            raise ValueError(f"a group point has at most {SLOTS} positions and velocities")


# --------------------------------------------------------------------------- per-group numbers


def axis_speed_limit(axis: AxisModel, period_ms: int, mode: FloatMode) -> tuple[int, int, float]:
    """(maxInc, max pulses/s, the speed check's limit in rad/s as float32) of one axis (§5.5).

    maxInc = trunc(pulses/s × period), then trunc(maxInc × 1000 / period) pulses/s,
    converted back to rad/s (m/s) as ConvertToRosPos does: always at or just below the
    datasheet speed.
    """
    inc = axis.max_increment(period_ms)
    pps = inc * 1000 // period_ms
    return inc, pps, from_pulse(pps, f32(axis.pulses_per_unit), mode)


@dataclass(frozen=True, slots=True, eq=False)
class GroupRules:
    """What MotoROS knows about one control group's axes once it has started.

    Build it with :meth:`from_model`. Tuples of 8: ``pulses_per_unit``,
    ``max_increment``, ``max_speed_pulses`` and ``valid`` are in controller order,
    ``max_speed`` and ``ros_to_slot`` in ROS order.
    """

    name: str
    joint_names: tuple[str, ...]
    """ROS order, one per axis."""
    period_ms: int
    float_mode: FloatMode
    ros_to_slot: tuple[int, ...]
    """Controller slot of each of the 8 ROS indices (axes first, then the unused slots)."""
    valid: tuple[bool, ...]
    """Slots that hold an axis (maxInc ≠ 0, §5.5)."""
    pulses_per_unit: tuple[float, ...]
    """PtoR / PtoM as float32 values; 1.0 for a slot without an axis (§5.7)."""
    max_increment: tuple[int, ...]
    """Most pulses an axis may move in one tick (maxInc, §5.5)."""
    max_speed_pulses: tuple[int, ...]
    """maxInc × 1000 / period truncated to whole pulses/s (§5.5)."""
    max_speed: tuple[float, ...]
    """The speed check's limit in rad/s (m/s), float32 values, 0.0 past the last axis."""
    b_axis_slave: bool = False
    """A 5-axis group whose B axis the controller keeps level (§5.7). Not supported:
    none of our models has one, and :meth:`from_model` never sets it."""

    @property
    def num_axes(self) -> int:
        return len(self.joint_names)

    @property
    def slot_to_ros(self) -> tuple[int, ...]:
        """ROS index of each controller slot (inverse of ``ros_to_slot``)."""
        inverse = [0] * SLOTS
        for ros, slot in enumerate(self.ros_to_slot):
            inverse[slot] = ros
        return tuple(inverse)

    def joint_at_slot(self, slot: int) -> str:
        """Joint name held by a controller slot, or a description of an empty slot."""
        return self.joint_name(self.slot_to_ros[slot])

    def joint_name(self, ros_index: int) -> str:
        """Joint name of a ROS index, or a description of an index past the last axis."""
        if ros_index < self.num_axes:
            return self.joint_names[ros_index]
        return f"unused slot {ros_index}"

    @classmethod
    def from_model(
        cls,
        group: GroupModel,
        controller: ControllerModel,
        pulses_per_unit: Sequence[float] | None = None,
    ) -> Self:
        """The constants MotoROS derives for ``group`` on ``controller``.

        ``pulses_per_unit`` (ROS order, one per axis) overrides the model's pulse ratios,
        as ``pymotoros interpolate --pulses-per-rad`` does; the speed limit in rad/s
        stays the model's (reference §11, last point). Called on a subclass, builds one.
        """
        n = group.num_axes
        period = controller.interpolation_period_ms
        mode = controller.float_mode
        if pulses_per_unit is not None:
            if len(pulses_per_unit) != n:
                raise ConfigError(
                    f"pulses per unit: group {group.name} has {n} axes, "
                    f"got {len(pulses_per_unit)} ratios"
                )
            for i, value in enumerate(pulses_per_unit):
                if not (math.isfinite(value) and value > 0):
                    raise ConfigError(
                        f"pulses per unit of {group.axes[i].name} must be a positive number, "
                        f"got {value!r}"
                    )

        used = set(group.moto_slots)
        ros_to_slot = tuple(group.moto_slots) + tuple(s for s in range(SLOTS) if s not in used)
        factors = [INVALID_AXIS_FACTOR] * SLOTS
        max_inc = [0] * SLOTS
        max_pps = [0] * SLOTS
        max_speed = [0.0] * SLOTS
        for i, axis in enumerate(group.axes):
            slot = ros_to_slot[i]
            inc, pps, max_speed[i] = axis_speed_limit(axis, period, mode)
            if pulses_per_unit is None:
                factor = f32(axis.pulses_per_unit)
            else:
                # Keep the model's limit in rad/s; the controller parameters follow the
                # new ratio (whole pulses per tick, whole pulses per second).
                # At least 1 pulse per tick, so that the axis stays an axis.
                factor = f32(pulses_per_unit[i])
                pps = int(max_speed[i] * factor)
                inc = max(1, pps * period // 1000)
            factors[slot] = factor
            max_inc[slot] = inc
            max_pps[slot] = pps
        return cls(
            name=group.name,
            joint_names=group.joint_names,
            period_ms=period,
            float_mode=mode,
            ros_to_slot=ros_to_slot,
            valid=tuple(v != 0 for v in max_inc),
            pulses_per_unit=tuple(factors),
            max_increment=tuple(max_inc),
            max_speed_pulses=tuple(max_pps),
            max_speed=tuple(max_speed),
        )


def group_rules(group: GroupModel, controller: ControllerModel) -> GroupRules:
    """:meth:`GroupRules.from_model`, remembered: the client asks for it per point.

    The same model objects come back point after point, so they are looked up by
    identity first: hashing a frozen model (every axis, every limit) costs more than
    the check it serves, tens of µs per point on a streamed plan."""
    global _recent_rules  # a cache of immutable values, swapped whole
    recent = _recent_rules  # one read: another thread may swap it meanwhile
    for known_group, known_controller, rules in recent:
        if known_group is group and known_controller is controller:
            return rules
    rules = _group_rules(group, controller)
    _recent_rules = ((group, controller, rules), *recent[:RECENT_RULES - 1])
    return rules


RECENT_RULES: Final = 8
"""(group, controller) pairs remembered by identity: a cell has at most 8 groups."""
_recent_rules: tuple[tuple[GroupModel, ControllerModel, GroupRules], ...] = ()
"""The last pairs asked for. A cache of immutable values, not state (two equal models
give equal rules); replaced whole, never changed in place, so threads can share it."""


@functools.lru_cache(maxsize=64)
def _group_rules(group: GroupModel, controller: ControllerModel) -> GroupRules:
    return GroupRules.from_model(group, controller)


# --------------------------------------------------------------------------- conversions


def to_pulses(pos_ros: Sequence[float], rules: GroupRules) -> tuple[int, ...]:
    """ConvertToMotoPos: 8 ROS-order positions → 8 pulse counts in controller order.

    Each value is rounded to float32 (the wire format) and ``(int)(value × factor)``
    truncates toward zero (§5.7, §11). Missing trailing values count as 0.0. Slots
    without an axis use the factor 1.0, as MotoROS does.
    """
    values = [f32(v) for v in pos_ros] + [0.0] * (SLOTS - len(pos_ros))
    out = [0] * SLOTS
    mode = rules.float_mode
    factors = rules.pulses_per_unit
    for ros, slot in enumerate(rules.ros_to_slot):
        out[slot] = pulse(values[ros], factors[slot], mode)
    return tuple(out)


def from_pulses(pulses: Sequence[int], rules: GroupRules) -> tuple[float, ...]:
    """ConvertToRosPos: 8 controller-order pulse counts → 8 ROS-order values (float32)."""
    mode = rules.float_mode
    factors = rules.pulses_per_unit
    return tuple(from_pulse(pulses[slot], factors[slot], mode) for slot in rules.ros_to_slot)


def feedback_pulses(pos_ros: Sequence[float], rules: GroupRules) -> tuple[int, ...]:
    """The 8 controller-order pulse counts that reported positions (ROS order) came from.

    The inverse of :func:`from_pulses`: the nearest whole pulse of ``value × factor``.
    ConvertToRosPos stores ``pulses / factor`` as float32 (relative error ≤ 2⁻²⁴), so
    this recovers the count exactly below 2²³ pulses (thousands of turns on any arm).
    A client that holds a settled feedback position gets the commanded pulses MotoROS
    compares a trajectory start with. Slots without an axis are 0.
    """
    out = [0] * SLOTS
    factors = rules.pulses_per_unit
    for ros, value in enumerate(pos_ros[: rules.num_axes]):
        slot = rules.ros_to_slot[ros]
        out[slot] = round(f32(value) * factors[slot])
    return tuple(out)


# --------------------------------------------------------------------------- the checks


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
    point: TrajPoint, commanded_pulses: Sequence[int], rules: GroupRules
) -> Refusal | None:
    """The sequence-0 checks (§3.4 step 5.3): start position and speed, interleaved.

    ``commanded_pulses`` is the group's commanded position (8 slots, controller order);
    MotoROS compares with it, not with the feedback. All 8 slots are tested, so a
    velocity of 1 rad/s or more in a slot past the last axis is refused.
    """
    requested = to_pulses(point.pos, rules)
    vel = _velocities(point)
    for i in range(SLOTS):
        diff = start_deviation(requested[i], commanded_pulses[i])
        if diff is not None:
            return _start_refusal(i, requested[i], commanded_pulses[i], diff, rules)
        refusal = check_axis_speed(i, vel[i], rules)
        if refusal is not None:
            return refusal
    return None


def check_speed(point: TrajPoint, rules: GroupRules) -> Refusal | None:
    """The sequence > 0 speed check (§3.4 step 6.2): ROS indices below the axis count."""
    vel = _velocities(point)
    for i in range(rules.num_axes):
        refusal = check_axis_speed(i, vel[i], rules)
        if refusal is not None:
            return refusal
    return None


def start_deviation(requested: int, commanded: int) -> int | None:
    """|requested − commanded| in pulses when it is beyond the start tolerance, else None."""
    diff = abs(requested - commanded)
    return diff if diff > START_TOLERANCE_PULSES else None


def check_axis_speed(i: int, v: float, rules: GroupRules) -> Refusal | None:
    """The speed test of ROS index ``i`` for a float32 velocity ``v`` (§5.5).

    ``trunc(|v|) > limit`` refuses, as C's integer ``abs()`` makes it; a velocity that
    does not fit an int32 (or is not a number) is refused for safety.
    """
    limit = rules.max_speed[i]
    speed = abs(v)
    if not speed <= INT32_MAX:  # NaN, inf, or beyond C's int conversion: refuse (safe)
        return _speed_refusal(i, speed, None, rules)
    whole = int(speed)  # C: abs((int)v), i.e. the velocity truncated toward zero
    if whole > limit:
        return _speed_refusal(i, speed, whole, rules)
    if speed > limit:
        logger.warning(
            "%s velocity %.6g rad/s is above the axis maximum %.6g rad/s, but MotoROS "
            "accepts it: its speed check truncates |v| to %d before comparing",
            rules.joint_name(i),
            speed,
            limit,
            whole,
        )
    return None


def _velocities(point: TrajPoint) -> list[float]:
    return [f32(v) for v in point.vel] + [0.0] * (SLOTS - len(point.vel))


def _code(subcode: InvalidSubcode) -> str:
    return f"{int(subcode)} {subcode.name}"


def _start_refusal(
    slot: int, requested: int, commanded: int, diff: int, rules: GroupRules
) -> Refusal:
    factor = rules.pulses_per_unit[slot]
    joint = rules.joint_at_slot(slot)
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


def _speed_refusal(i: int, speed: float, whole: int | None, rules: GroupRules) -> Refusal:
    limit = rules.max_speed[i]
    joint = rules.joint_name(i)
    if i < rules.num_axes:
        slot = rules.ros_to_slot[i]
        where = (
            f"the axis maximum {limit:.6g} rad/s ({rules.max_speed_pulses[slot]} pulses/s, "
            f"{rules.max_increment[slot]} pulses per {rules.period_ms} ms tick)"
        )
        per_second = f" = {speed * rules.pulses_per_unit[slot]:.0f} pulses/s"
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
