"""Per-group constants of the interpolator, and the pulse ↔ joint conversions (§5.5, §5.7).

Orders: a *ROS index* counts joints as the wire carries them; a *slot* is the
controller's (Moto) axis position. They differ for 7-axis arms (ROS S,L,E,U,R,B,T,
controller S,L,U,R,B,T,E) and for groups whose axes are not contiguous. Every pulse
tuple here has 8 slots in controller order; every joint tuple has 8 values in ROS
order.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from pymotoros.models.rules import GroupRules, from_pulses, to_pulses

__all__ = ["GroupAxes", "from_pulses", "to_pulses"]

F32Array = npt.NDArray[np.float32]
IntpArray = npt.NDArray[np.intp]


@dataclass(frozen=True, slots=True, eq=False)
class GroupAxes(GroupRules):
    """:class:`~pymotoros.models.rules.GroupRules` plus the arrays of the vectorised engine.

    Build it with :meth:`from_model` (inherited): the numbers come from the shared
    rules, computed once; only their numpy forms are derived here.
    """

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
