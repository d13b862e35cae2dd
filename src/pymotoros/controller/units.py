"""Pulses → joint units for the state stream, vectorised.

Exactly :func:`pymotoros.motion.from_pulses` (ConvertToRosPos, §5.7: ``pulse / factor``
evaluated as the controller build does and stored as float32, then put in ROS order),
done for all slots in one numpy operation: feedback is converted for every state
client every 25 ms, and the element-wise path costs several µs per value.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion import GroupAxes


class RosConverter:
    """Converts 8 controller-order pulse values of one group to 8 ROS-order values."""

    __slots__ = ("_factors", "_order", "_single")

    def __init__(self, axes: GroupAxes) -> None:
        self._order = np.array(axes.ros_to_slot, dtype=np.intp)
        factors = [axes.pulses_per_unit[s] for s in axes.ros_to_slot]
        self._single = axes.float_mode is FloatMode.STRICT_SINGLE
        self._factors: npt.NDArray[np.floating] = (
            np.array(factors, dtype=np.float32)
            if self._single
            else np.array(factors, dtype=np.longdouble)
        )

    def __call__(self, pulses: Sequence[int]) -> tuple[float, ...]:
        values = np.asarray(pulses, dtype=np.int64)[self._order]
        if self._single:
            out = values.astype(np.float32) / self._factors
        else:
            out = (values.astype(np.longdouble) / self._factors).astype(np.float32)
        return tuple(out.tolist())
