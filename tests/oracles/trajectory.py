"""The trajectory intake's reference route: JOINT_TRAJ_PT_FULL through a Process.

The library answers a point at once (``TrajectoryPoints.trajectory_point``), its
float32 form made once and the speed limits screened before ``check_speed``. Here is
§3.4 read literally, as the controller answered before: every point a Process, the
point turned into a :class:`~pymotoros.motion.TrajPoint`, ``check_time`` and
``check_speed`` always run, the interpolator making its own float32 point
(``GroupInterpolator.set_pending``). :func:`through_a_process` installs it.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from pymotoros.controller.api import PointData
from pymotoros.controller.processes import Process
from pymotoros.controller.replies import invalid, reply
from pymotoros.controller.trajectory import TrajectoryPoints
from pymotoros.motion import SLOTS, TrajPoint, check_speed, check_time
from pymotoros.protocol.constants import REQUIRED_POINT_FIELDS, ResultCode


def trajectory_point(self: TrajectoryPoints, sequence: int, point: PointData) -> Process:
    """JOINT_TRAJ_PT_FULL (14): §3.4, in its order, every check run."""
    if not self._flags.motion_ready:
        return self._readiness.not_ready()
    g = point.group_no
    if not 0 <= g < self._num_groups:
        return self._bad_group(g)
    required = int(REQUIRED_POINT_FIELDS)
    if point.valid_fields & required != required:
        return self._insufficient(point)
    traj = TrajPoint(point.time, tuple(point.pos[:SLOTS]), tuple(point.vel[:SLOTS]))
    refusal = check_time(traj)
    if refusal is not None:
        return invalid(int(refusal.subcode), f"point {sequence} of group {g}: {refusal.message}")
    if sequence == 0:
        if self._machine.state.eco:
            yield from self._commands.eco_reenable()
        return self._start_group(g, traj, sequence)
    if sequence < 0:
        return self._bad_sequence(sequence)
    interp = self._interpolators[g]
    if interp.pending:
        return self._busy_replies[g]
    refusal = check_speed(traj, self._axes[g])
    if refusal is not None:
        return invalid(int(refusal.subcode), f"point {sequence} of group {g}: {refusal.message}")
    interp.set_pending(traj)
    return reply(ResultCode.SUCCESS)


@contextmanager
def through_a_process() -> Iterator[None]:
    """Controllers answer JOINT_TRAJ_PT_FULL through :func:`trajectory_point` inside."""
    saved = TrajectoryPoints.trajectory_point
    TrajectoryPoints.trajectory_point = trajectory_point  # type: ignore[assignment]
    try:
        yield
    finally:
        TrajectoryPoints.trajectory_point = saved  # type: ignore[method-assign]
