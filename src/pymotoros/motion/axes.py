"""Per-group constants of the interpolator, and the pulse ↔ joint conversions (§5.5, §5.7).

Orders: a *ROS index* counts joints as the wire carries them; a *slot* is the
controller's (Moto) axis position. They differ for 7-axis arms (ROS S,L,E,U,R,B,T,
controller S,L,U,R,B,T,E) and for groups whose axes are not contiguous. Every pulse
tuple here has 8 slots in controller order; every joint tuple has 8 values in ROS
order.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from pymotoros.errors import ConfigError
from pymotoros.models import ControllerModel, FloatMode, GroupModel
from pymotoros.motion.constants import INVALID_AXIS_FACTOR, SLOTS
from pymotoros.motion.numerics import f32, from_pulse, pulse

F32Array = npt.NDArray[np.float32]
IntpArray = npt.NDArray[np.intp]


@dataclass(frozen=True, slots=True, eq=False)
class GroupAxes:
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

    # Derived arrays for the vectorised engine (ROS order, first ``num_axes`` entries).
    factors_ros: F32Array = field(init=False, repr=False)
    """Pulse ratio of each ROS-order axis, float32."""
    columns: IntpArray = field(init=False, repr=False)
    """ROS index of each output column; columns are the valid slots in ascending order."""
    axis_slots: tuple[int, ...] = field(init=False, repr=False)
    """The valid slots in ascending order (the columns of offline output)."""
    identity_columns: bool = field(init=False, repr=False)
    """True when ROS index j is the j-th valid slot (every group but a 7-axis arm)."""
    axis_slots_array: IntpArray = field(init=False, repr=False)
    contiguous: bool = field(init=False, repr=False)
    """The axes occupy slots 0 … num_axes − 1 (every model we ship)."""
    factors_ros_list: list[float] = field(init=False, repr=False)
    columns_list: list[int] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = len(self.joint_names)
        slots = self.ros_to_slot[:n]
        object.__setattr__(
            self,
            "factors_ros",
            np.array([self.pulses_per_unit[s] for s in slots], dtype=np.float32),
        )
        ordered = sorted(range(n), key=lambda i: slots[i])
        object.__setattr__(self, "columns", np.array(ordered, dtype=np.intp))
        object.__setattr__(self, "axis_slots", tuple(sorted(slots)))
        object.__setattr__(self, "identity_columns", ordered == list(range(n)))
        object.__setattr__(self, "axis_slots_array", np.array(sorted(slots), dtype=np.intp))
        object.__setattr__(self, "contiguous", sorted(slots) == list(range(n)))
        object.__setattr__(self, "factors_ros_list", self.factors_ros.tolist())
        object.__setattr__(self, "columns_list", ordered)

    def take(self, pulses: Sequence[int]) -> list[int]:
        """The valid slots of an 8-slot pulse tuple, in ascending slot order."""
        return [pulses[s] for s in self.axis_slots]

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
        ros = self.slot_to_ros[slot]
        return self.joint_name(ros)

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
    ) -> GroupAxes:
        """The constants MotoROS derives for ``group`` on ``controller``.

        ``pulses_per_unit`` (ROS order, one per axis) overrides the model's pulse ratios,
        as ``pymotoros interpolate --pulses-per-rad`` does; the speed limit in rad/s
        stays the model's (reference §11, last point).
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
            model_factor = f32(axis.pulses_per_unit)
            inc = axis.max_increment(period)
            pps = inc * 1000 // period
            max_speed[i] = from_pulse(pps, model_factor, mode)
            if pulses_per_unit is None:
                factor = model_factor
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


def to_pulses(pos_ros: Sequence[float], axes: GroupAxes) -> tuple[int, ...]:
    """ConvertToMotoPos: 8 ROS-order positions → 8 pulse counts in controller order.

    Each value is rounded to float32 (the wire format) and ``(int)(value × factor)``
    truncates toward zero (§5.7, §11). Missing trailing values count as 0.0. Slots
    without an axis use the factor 1.0, as MotoROS does.
    """
    values = [f32(v) for v in pos_ros] + [0.0] * (SLOTS - len(pos_ros))
    out = [0] * SLOTS
    mode = axes.float_mode
    factors = axes.pulses_per_unit
    for ros, slot in enumerate(axes.ros_to_slot):
        out[slot] = pulse(values[ros], factors[slot], mode)
    return tuple(out)


def from_pulses(pulses: Sequence[int], axes: GroupAxes) -> tuple[float, ...]:
    """ConvertToRosPos: 8 controller-order pulse counts → 8 ROS-order values (float32)."""
    mode = axes.float_mode
    factors = axes.pulses_per_unit
    return tuple(from_pulse(pulses[slot], factors[slot], mode) for slot in axes.ros_to_slot)
