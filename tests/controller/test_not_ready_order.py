"""NOT_READY subcode order (reference §4.2): the first matching test wins."""

from __future__ import annotations

from pymotoros.controller import PendantMode, VirtualController
from pymotoros.controller.signals import PFL_STOP
from pymotoros.protocol.constants import NotReadySubcode as Nr

from .helpers import CMD, command
from .states import inc_move_error, pfl, ready, settle_monitor


def subcode(vc: VirtualController) -> int:
    settle_monitor(vc)
    return command(vc, CMD.CHECK_MOTION_READY).subcode


def test_everything_wrong_peels_off_in_order() -> None:
    """Switch every condition on, then remove them one by one, checking each subcode."""
    vc = ready()
    vc.force_io(PFL_STOP, 1)  # PFL event while the job is ready: latch set
    settle_monitor(vc)
    vc.force_io(PFL_STOP, 0)
    vc.motoros.latch_inc_move_error("test")  # the latch the IncMove task sets
    vc.set_hold(True)
    vc.raise_error(2010, 0, "error")
    vc.set_remote(False)
    vc.set_mode(PendantMode.TEACH)
    vc.press_estop(True)  # also cuts servo power
    vc.raise_alarm(4100, 0, "minor alarm")

    assert subcode(vc) == Nr.ALARM
    vc.reset()  # clears the alarm and the error together
    vc.raise_error(2010, 0, "error")
    assert subcode(vc) == Nr.ERROR
    vc.reset()
    assert subcode(vc) == Nr.ESTOP
    vc.press_estop(False)
    assert subcode(vc) == Nr.NOT_PLAY
    vc.set_mode(PendantMode.PLAY)
    assert subcode(vc) == Nr.NOT_REMOTE
    vc.set_remote(True)
    assert subcode(vc) == Nr.SERVO_OFF
    vc.set_servo(True)
    vc.run_ticks(200)
    assert subcode(vc) == Nr.HOLD
    vc.set_hold(False)
    # 5011 and 5012 come before 5008 NOT_STARTED although the job is not running
    assert subcode(vc) == Nr.PFL_ACTIVE
    vc.motoros.clear_pfl_latch()
    assert subcode(vc) == Nr.INC_MOVE_ERROR
    vc.motoros.clear_inc_move_error()
    assert subcode(vc) == Nr.NOT_STARTED


def test_eco_mode_reads_as_servo_off() -> None:
    vc = ready()
    vc.set_eco(True)
    settle_monitor(vc)
    # eco does not change the motion-ready flag (§4.1) …
    assert command(vc, CMD.CHECK_MOTION_READY).ok
    assert vc.robot_status().drives_powered == 0
    # … but when something else makes it false, 5006 is reported before 5007/5008
    vc.set_hold(True)
    assert subcode(vc) == Nr.SERVO_OFF


def test_pfl_before_not_started() -> None:
    vc = pfl()
    vc.force_io(50070, 0)  # the job stops as well
    assert subcode(vc) == Nr.PFL_ACTIVE


def test_inc_move_error_before_waiting_ros() -> None:
    vc = inc_move_error()
    assert subcode(vc) == Nr.INC_MOVE_ERROR


def test_skillsend_when_889_seen_without_edge() -> None:
    """OT#889 on without a rising edge the monitor saw: job-ready false → 5010."""
    vc = ready()
    vc.motoros.forget_job_ready()
    vc.motoros.status_update()
    assert subcode(vc) == Nr.SKILLSEND
    assert "rising edge" in command(vc, CMD.CHECK_MOTION_READY).detail
