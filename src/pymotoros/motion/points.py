"""Trajectory points as the motion engine takes them, and their float32 form.

A :class:`TrajPoint` is what arrives on the wire for one group: time in seconds,
positions and velocities in ROS order (rad, or m for a linear axis). The wire carries
float32, so the engine rounds every value to float32 first, exactly as a client that
packs a Python float does (§11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.constants import SLOTS
from pymotoros.motion.numerics import seconds_to_ms

F32Array = npt.NDArray[np.float32]


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


@dataclass(frozen=True, slots=True, eq=False)
class GroupPoint:
    """A point as a group's interpolation state holds it (§5.2): integer ms and float32."""

    time_ms: int
    pos: F32Array
    """8 float32 positions, ROS order."""
    vel: F32Array
    """8 float32 velocities, ROS order."""

    @classmethod
    def from_traj(cls, point: TrajPoint, mode: FloatMode) -> GroupPoint:
        return cls(seconds_to_ms(point.time, mode), padded_f32(point.pos), padded_f32(point.vel))


def padded_f32(values: tuple[float, ...]) -> F32Array:
    """The 8 float32 slots of a wire array, zero-filled after the given values."""
    out = np.zeros(SLOTS, dtype=np.float32)
    with np.errstate(over="ignore"):
        out[: len(values)] = np.asarray(values, dtype=np.float64)
    return out
