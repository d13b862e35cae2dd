"""The MotoROS 1.9.12 motion engine, bit-faithful: pure numerics, no clock, no I/O.

What the controller, ``pymotoros interpolate`` and the benchmarks use:

* :class:`GroupAxes` – a group's constants (``GroupAxes.from_model``);
  :func:`to_pulses` / :func:`from_pulses` – ConvertToMotoPos / ConvertToRosPos;
* :func:`check_start`, :func:`check_speed`, :func:`check_time` → :class:`Refusal`
  (defined once in :mod:`pymotoros.models.rules`, which the client shares);
* :class:`TrajPoint` – one point of one group (s, ROS order);
* :class:`GroupInterpolator` – one group's state and AddToIncQueue task;
  :func:`inc_move` – one IncMove turn for all groups; :func:`add_pulses`;
* :func:`interpolate` / :func:`interpolate_arrays` – the vectorised offline engine.

Section numbers in docstrings refer to ``shared/reference/motoros-1.9.12.md``; the
numerics are described in ``docs/motion.md``.
"""

from pymotoros.models.rules import (
    START_TOLERANCE_PULSES,
    Refusal,
    check_speed,
    check_start,
    check_time,
)
from pymotoros.motion.axes import GroupAxes, from_pulses, to_pulses
from pymotoros.motion.constants import QUEUE_SIZE, SLOTS
from pymotoros.motion.incmove import add_pulses, inc_move
from pymotoros.motion.interpolator import GroupInterpolator
from pymotoros.motion.offline import interpolate, interpolate_arrays
from pymotoros.motion.points import GroupPoint, TrajPoint
from pymotoros.motion.queue import ZERO_PULSES, Increment, IncrementQueue

__all__ = [
    "QUEUE_SIZE",
    "SLOTS",
    "START_TOLERANCE_PULSES",
    "ZERO_PULSES",
    "GroupAxes",
    "GroupInterpolator",
    "GroupPoint",
    "Increment",
    "IncrementQueue",
    "Refusal",
    "TrajPoint",
    "add_pulses",
    "check_speed",
    "check_start",
    "check_time",
    "from_pulses",
    "inc_move",
    "interpolate",
    "interpolate_arrays",
    "to_pulses",
]
