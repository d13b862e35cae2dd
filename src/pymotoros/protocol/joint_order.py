"""ROS joint order on the wire vs the controller's axis order (reference §5.7).

The wire carries joints in the order the robot's URDF names them; the controller
numbers its axes differently for two kinds of robot group:

* 7-axis arms: the wire says S, L, E, U, R, B, T but the controller keeps the
  elbow (E) last: S, L, U, R, B, T, E.
* groups with fewer than 6 axes (delta, SCARA, palletiser, MPL picker): the
  controller leaves holes (SLU--T-), the wire packs the real axes together (SLUT).

Everything else (6-axis arms, base and station groups) is the identity.

A map here is a permutation ``ros_to_slot`` of the 8 controller slots: entry
``i`` is the controller slot that ROS index ``i`` comes from. The group's axes
come first; the unused slots follow in ascending order, so that conversions in
both directions are lossless. All functions are pure and work on any element
type (floats, pulses, names).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final, TypeVar

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol.constants import MAX_PULSE_AXES

__all__ = [
    "IDENTITY",
    "SEVEN_AXIS",
    "check_map",
    "packed_map",
    "ros_to_slot_map",
    "to_controller_order",
    "to_ros_order",
]

_T = TypeVar("_T")

SEVEN_AXIS_COUNT: Final = 7
"""Axes of the arms whose elbow the controller stores last (§5.7)."""

FULL_ARM_AXES: Final = 6
"""Robot groups with fewer axes than this have their valid slots packed (§5.7)."""

IDENTITY: Final[tuple[int, ...]] = tuple(range(MAX_PULSE_AXES))
"""6-axis robots, base axes and stations: ROS index i is controller slot i."""

SEVEN_AXIS: Final[tuple[int, ...]] = (0, 1, 6, 2, 3, 4, 5, 7)
"""ROS S,L,E,U,R,B,T from controller S,L,U,R,B,T,E: ROS[2] = slot 6, ROS[k] = slot k−1."""


def check_map(ros_to_slot: Sequence[int]) -> tuple[int, ...]:
    """The map as a tuple, if it is a permutation of the 8 slots; else LocalProtocolError."""
    mapping = tuple(ros_to_slot)
    if sorted(mapping) != list(IDENTITY):
        raise LocalProtocolError(
            f"joint map {mapping} is not a permutation of slots 0..{MAX_PULSE_AXES - 1}"
        )
    return mapping


def packed_map(valid: Sequence[bool]) -> tuple[int, ...]:
    """Pack the valid controller slots into ROS indices 0..n−1 (SLU--T- → SLUT)."""
    flags = _eight(valid, "valid")
    used = [slot for slot, ok in enumerate(flags) if ok]
    return tuple(used + [slot for slot, ok in enumerate(flags) if not ok])


def ros_to_slot_map(valid: Sequence[bool], *, robot: bool) -> tuple[int, ...]:
    """The map MotoROS applies to a group, from its valid axes (max increment ≠ 0).

    ``robot`` is True for R1..R4 groups; base and station groups never reorder.
    """
    flags = _eight(valid, "valid")
    count = sum(1 for ok in flags if ok)
    if robot and count == SEVEN_AXIS_COUNT:
        return SEVEN_AXIS
    if robot and count < FULL_ARM_AXES:
        return packed_map(flags)
    return IDENTITY


def to_controller_order(ros_values: Sequence[_T], ros_to_slot: Sequence[int]) -> tuple[_T, ...]:
    """8 values in controller slot order from 8 (or more; the rest is ignored) in ROS order."""
    values = _eight(ros_values, "ros_values")
    out: list[_T] = list(values)
    for ros_index, slot in enumerate(ros_to_slot):
        out[slot] = values[ros_index]
    return tuple(out)


def to_ros_order(slot_values: Sequence[_T], ros_to_slot: Sequence[int]) -> tuple[_T, ...]:
    """8 values in ROS order from 8 (or more; the rest is ignored) in controller order."""
    values = _eight(slot_values, "slot_values")
    return tuple(values[slot] for slot in ros_to_slot)


def _eight(values: Sequence[_T], name: str) -> Sequence[_T]:
    if len(values) < MAX_PULSE_AXES:
        raise LocalProtocolError(f"{name} has {len(values)} slots, need {MAX_PULSE_AXES}")
    return values[:MAX_PULSE_AXES]
