"""Trajectory points as the motion engine takes them, and their float32 form.

A :class:`TrajPoint` is what arrives on the wire for one group: time in seconds,
positions and velocities in ROS order (rad, or m for a linear axis). The wire carries
float32, so the engine rounds every value to float32 first, exactly as a client that
packs a Python float does (§11).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final

from pymotoros.models import FloatMode
from pymotoros.models.rules import TrajPoint as TrajPoint
from pymotoros.motion.constants import INT32_MAX, INT32_MIN, SLOTS
from pymotoros.motion.numerics import f32, f32_tuple, float32_seconds_to_ms


@dataclass(frozen=True, slots=True)
class GroupPoint:
    """A point as a group's interpolation state holds it (§5.2): integer ms, float32 values."""

    time_ms: int
    pos: tuple[float, ...]
    """8 float32 positions (as Python floats), ROS order."""
    vel: tuple[float, ...]
    """8 float32 velocities, ROS order."""
    tame: bool = True
    """Every value is finite and below 10¹⁵ in magnitude, so no float32 or float64
    operation of the interpolation can overflow (the engine then skips numpy's
    floating-point error handling)."""
    raw: bytes = field(default=b"", compare=False, repr=False)
    """``pos`` then ``vel`` as 16 little-endian float32 (empty if not made yet): the
    tick engine stacks many points into one array from these bytes."""

    @classmethod
    def from_traj(cls, point: TrajPoint, mode: FloatMode) -> GroupPoint:
        return cls.from_values(point.time, point.pos, point.vel, mode)

    @classmethod
    def from_values(
        cls, time: float, pos_in: Sequence[float], vel_in: Sequence[float], mode: FloatMode
    ) -> GroupPoint:
        """:meth:`from_traj` without the TrajPoint (at most 8 positions and velocities)."""
        try:  # the time, the positions and the velocities rounded to float32 at once
            raw = _TIMED.pack(
                time, *pos_in, *_ZEROS[len(pos_in) :], *vel_in, *_ZEROS[len(vel_in) :]
            )
        except OverflowError:  # beyond float32: the wire would carry ±inf
            raw = _TIMED.pack(f32(time), *f32_tuple(pos_in, SLOTS), *f32_tuple(vel_in, SLOTS))
        values = _TIMED.unpack(raw)
        pos, vel = values[1 : SLOTS + 1], values[SLOTS + 1 :]
        tame = sum(map(abs, pos)) + sum(map(abs, vel)) < TAME_LIMIT  # False for inf and NaN
        product = values[0] * 1000.0  # exact: float32 × 1000 has at most 34 bits
        if mode is FloatMode.X87_EXTENDED and _INT32_LOW < product < _INT32_HIGH:
            time_ms = int(product)  # float32_seconds_to_ms, inlined for the x87
        else:
            time_ms = float32_seconds_to_ms(values[0], mode)
        return cls(time_ms, pos, vel, tame, raw[4:])

    def packed(self) -> bytes:
        """:attr:`raw`, made now if the point was built without it."""
        return self.raw or _POINT.pack(*self.pos, *self.vel)


TAME_LIMIT: Final = 1e15
_INT32_LOW: Final = float(INT32_MIN) - 1.0
_INT32_HIGH: Final = float(INT32_MAX) + 1.0
_POINT: Final = struct.Struct(f"<{2 * SLOTS}f")
_TIMED: Final = struct.Struct(f"<{2 * SLOTS + 1}f")
_ZEROS: Final = (0.0,) * SLOTS


ORIGIN = GroupPoint(0, (0.0,) * SLOTS, (0.0,) * SLOTS)
"""The state of a group that has never started (MotoROS's zero-initialised struct)."""
