"""Trajectory files, time parameterisation and the offline pre-flight check.

The layer between :mod:`pymotoros.motion` (the bit-exact engine it reuses) and the
CLI: :class:`Trajectory` is one file model read and written as the CSV of
``pymotoros interpolate``, as JSON and as the YAML ``rostopic echo`` prints;
:func:`plan_waypoints` times waypoints within the model's limits (toppra);
:func:`check_trajectory` predicts what MotoROS 1.9.12 will do with a trajectory,
plus what it never checks. The client never imports this package (it is wire only).
"""

from pymotoros.trajectory.check import (
    CheckReport,
    Refused,
    Warning_,
    check_against_cell,
    check_trajectory,
)
from pymotoros.trajectory.files import Trajectory, read_trajectory_file, write_trajectory_file
from pymotoros.trajectory.planning import plan_waypoints

__all__ = [
    "CheckReport",
    "Refused",
    "Trajectory",
    "Warning_",
    "check_against_cell",
    "check_trajectory",
    "plan_waypoints",
    "read_trajectory_file",
    "write_trajectory_file",
]
