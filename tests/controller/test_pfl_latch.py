"""The "PFL during ROS move" latch on its own keeps motion NOT_READY (reference §4.1).

After a PFL contact while moving, the increment refusal also latches 5012, which hides
whether the PFL latch itself is honoured. Here the PFL stop signal rises and falls while
the robot stands in trajectory mode (the status monitor's PFL edge, §2.6): nothing was
refused, only the PFL latch is set, and it alone must keep every motion request out
until START_TRAJ_MODE clears it (§3.2 step 1).
"""

from __future__ import annotations

from pymotoros.controller.signals import PFL_STOP
from pymotoros.protocol.constants import NotReadySubcode, ResultCode

from .helpers import CMD, command, complete, current_pos, point
from .states import ready, settle_monitor


def test_the_pfl_latch_alone_refuses_motion_until_start_traj_mode() -> None:
    vc = ready()
    assert command(vc, CMD.CHECK_MOTION_READY).ok
    vc.force_io(PFL_STOP, 1)
    settle_monitor(vc)
    vc.force_io(PFL_STOP, 0)  # the signal is gone ...
    settle_monitor(vc)
    assert vc.motoros.pfl_during_move  # ... the latch stays
    assert not vc.motoros.inc_move_error  # nothing was moving: no 5012 to hide behind
    check = command(vc, CMD.CHECK_MOTION_READY)
    assert not check.ok
    assert check.subcode == NotReadySubcode.PFL_ACTIVE
    refused = complete(vc, vc.trajectory_point(0, point(0, 0.0, current_pos(vc))))
    assert (refused.result, refused.subcode) == (ResultCode.NOT_READY, NotReadySubcode.PFL_ACTIVE)
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert not vc.motoros.pfl_during_move
    assert command(vc, CMD.CHECK_MOTION_READY).ok
    assert complete(vc, vc.trajectory_point(0, point(0, 0.0, current_pos(vc)))).ok
