"""The safety unit (PFL contact and clamping, FSU at run time) seen from MotoROS, virtual time."""

from __future__ import annotations

import pytest

from pymotoros.controller import VirtualController, cell_from_dict, default_cell, signals
from pymotoros.controller.assembly import assemble
from pymotoros.controller.safety import PFL_STOP_MS
from pymotoros.controller.safety.fsu import FsuFunction
from pymotoros.protocol.constants import NotReadySubcode, ResultCode

from .helpers import CMD, command, current_pos, point, send, start_at_current, tick_until

MOVE_S = 2.0


def moving_hc10() -> VirtualController:
    """An HC10 (PFL option on by default) in the middle of a 2 s move of joint 1."""
    vc = VirtualController()
    assert vc.cell.pfl
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert start_at_current(vc).ok
    assert send(vc, 1, point(0, MOVE_S, [0.5, 0, 0, 0, 0, 0])).ok
    vc.run_ticks(100)  # 0.4 s into the move
    assert vc.in_motion()
    return vc


def test_pfl_contact_stops_within_one_tick_latches_5011_and_recovers() -> None:
    vc = moving_hc10()
    before = vc.snapshot().groups[0].command_pulse
    contact_ms = vc.time_ms
    vc.pfl_event("contact")
    assert vc.io.get(signals.PFL_STOP) == 1
    vc.tick()
    stopped = vc.snapshot().groups[0].command_pulse
    assert stopped == before  # no further increment executed
    vc.tick()
    assert not vc.has_queued_motion()  # the monitor cleared the queues
    check = command(vc, CMD.CHECK_MOTION_READY)
    assert not check.ok
    assert check.subcode == NotReadySubcode.PFL_ACTIVE
    tick_until(vc, lambda: not vc.io.get(signals.PFL_STOP), "PFL stop clears")
    assert vc.time_ms - contact_ms == pytest.approx(PFL_STOP_MS, abs=vc.period_ms)
    tick_until(vc, lambda: not vc.in_motion(), "robot stands still", max_ticks=20)
    # still latched after the signal cleared: only START_TRAJ_MODE clears it
    refused = send(vc, 2, point(0, 0.0, current_pos(vc)))
    assert (refused.result, refused.subcode) == (ResultCode.NOT_READY, NotReadySubcode.PFL_ACTIVE)
    assert vc.robot_status().in_motion == 0
    assert command(vc, CMD.START_TRAJ_MODE).ok
    here = current_pos(vc)
    assert send(vc, 0, point(0, 0.0, here)).ok
    assert send(vc, 1, point(0, 1.0, [0.1, 0, 0, 0, 0, 0])).ok
    tick_until(vc, vc.has_queued_motion, "second move starts", max_ticks=5)
    tick_until(vc, lambda: not vc.in_motion(), "second move done")
    assert current_pos(vc)[0] == pytest.approx(0.1, abs=1e-4)


def test_pfl_clamping_retreats_along_the_last_commanded_motion() -> None:
    vc = moving_hc10()
    vc.run_ticks(-(-100 // vc.period_ms))  # 100 ms more of recorded motion
    at_contact = current_pos(vc)[0]
    vc.pfl_event("clamping", retreat_ms=100)
    tick_until(vc, lambda: bool(vc.io.get(signals.PFL_ESCAPE)), "escape on", max_ticks=200)
    assert not vc.io.get(signals.PFL_STOP)
    tick_until(vc, lambda: not vc.io.get(signals.PFL_ESCAPE), "escape off", max_ticks=50)
    retreated = current_pos(vc)[0]
    assert retreated < at_contact  # moved back towards the start
    tick_until(vc, lambda: not vc.in_motion(), "still", max_ticks=20)
    assert vc.motoros.pfl_during_move
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert send(vc, 0, point(0, 0.0, current_pos(vc))).ok


def test_pfl_refusals_say_why() -> None:
    vc = VirtualController()
    with pytest.raises(ValueError, match="stands still"):
        vc.pfl_event("contact")
    with pytest.raises(ValueError, match="contact' or 'clamping"):
        vc.pfl_event("bump")
    off = VirtualController(cell_from_dict({"controller": {"pfl": False}}))
    with pytest.raises(ValueError, match="PFL option is off"):
        off.pfl_event("contact")
    gp = VirtualController(cell_from_dict({"robot": {"model": "gp7"}}))
    with pytest.raises(ValueError, match="not an HC"):
        gp.pfl_event("contact")
    dx = VirtualController(cell_from_dict({"controller": {"model": "dx200"}}))
    with pytest.raises(ValueError, match="only YRC1000"):
        dx.pfl_event("contact")


def _long_move(fsu_pct_mid: int | None) -> tuple[int, tuple[int, ...], float]:
    vc = VirtualController(cell_from_dict({"controller": {"pfl": False}}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert start_at_current(vc).ok
    limit = [0.8 * v for v in vc.motoros.axes[0].max_speed[:6]]
    assert send(vc, 1, point(0, 1.0, limit, limit)).ok
    start = vc.time_ms
    vc.run_ticks(50)
    if fsu_pct_mid is not None:
        vc.set_fsu(joint_speed_pct=fsu_pct_mid)
    mid = current_pos(vc)[0]
    vc.run_ticks(50)
    progress = current_pos(vc)[0] - mid
    tick_until(
        vc,
        lambda: not vc.has_queued_motion() and not any(map(any, vc.motoros.unprocessed_pulses)),
        "every pulse executed",
    )
    assert not vc.motoros.inc_move_error
    return vc.time_ms - start, vc.snapshot().groups[0].command_pulse, progress


def test_fsu_switched_mid_trajectory_slows_from_the_next_tick_and_ends_at_the_target() -> None:
    free_ms, free_end, free_progress = _long_move(None)
    slow_ms, slow_end, slow_progress = _long_move(25)
    assert slow_end == free_end
    assert slow_ms > 1.3 * free_ms
    assert slow_progress < 0.5 * free_progress


def test_fsu_switches_and_refusals() -> None:
    vc = VirtualController()
    assert vc.safety.fsu.active.joint_speed_pct is None
    vc.set_fsu(joint_speed_pct=50)
    assert vc.safety.fsu.active.joint_speed_pct == 50
    assert vc.safety.fsu.limits() is not None
    with pytest.raises(ValueError, match=r"1\.\.100"):
        vc.set_fsu(joint_speed_pct=0)
    with pytest.raises(ValueError, match="not both"):
        vc.set_fsu(joint_speed_pct=10, off=True)
    vc.set_fsu(off=True)
    assert vc.safety.fsu.limits() is None
    # the controller builds its FSU with its kinematics: the TCP limit engages the clip
    vc.set_fsu(tcp_speed_mm_s=250.0)
    assert vc.safety.fsu.active.tcp_speed_mm_s == 250.0
    assert vc.safety.fsu.limits() is not None
    # an FSU built without kinematics (no tcp_limiter) refuses a TCP limit, saying why
    ctx = assemble(default_cell(), seed=0, on_skill=lambda slave, text: None).ctx
    alone = FsuFunction(ctx.axes, ctx.servos, None)
    with pytest.raises(ValueError, match="kinematics"):
        alone.set(tcp_speed_mm_s=250.0)
    assert alone.limits() is None


TCP_LIMIT_MM_S = 100.0


def _tcp_move(tcp_limit: float | None) -> tuple[tuple[int, ...], list[float], list[float], int]:
    """A fast 1 s move of joints 1-3 with an optional FSU TCP limit from the start; per
    tick the TCP speed of the command and of the feedback, the end pulses, the ticks."""
    vc = VirtualController(cell_from_dict({"controller": {"pfl": False}}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert start_at_current(vc).ok
    if tcp_limit is not None:
        vc.set_fsu(tcp_speed_mm_s=tcp_limit)
    assert send(vc, 1, point(0, 1.0, [0.6, 0.4, -0.3, 0, 0, 0])).ok
    commanded: list[float] = []
    feedback: list[float] = []
    ticks = 0
    while vc.has_queued_motion() or any(map(any, vc.motoros.unprocessed_pulses)) or ticks < 20:
        vc.run_ticks(1)
        ticks += 1
        assert ticks < 10_000, "the move never ended"
        tcp = vc.snapshot().groups[0].tcp
        assert tcp is not None
        commanded.append(tcp.command_speed_mm_s)
        feedback.append(tcp.feedback_speed_mm_s)
    vc.run_ticks(50)  # let the feedback settle
    return vc.snapshot().groups[0].command_pulse, commanded, feedback, ticks


def test_fsu_tcp_speed_limit_holds_and_the_move_still_ends_at_its_target() -> None:
    free_end, free_cmd, _, free_ticks = _tcp_move(None)
    end, cmd, fb, ticks = _tcp_move(TCP_LIMIT_MM_S)
    assert max(free_cmd) > 3 * TCP_LIMIT_MM_S  # the move would be much faster unlimited
    assert end == free_end  # MotoROS's compensation delivers every pulse
    assert ticks > 2 * free_ticks
    # per tick, never above the limit (rounding down per axis; 0.5 % for the chord-vs-arc
    # difference of one 4 ms step); the feedback follows the command (+1 tick of slack)
    assert max(cmd) <= TCP_LIMIT_MM_S * 1.005
    assert max(fb[1:]) <= TCP_LIMIT_MM_S * 1.005
    assert max(cmd) > 0.9 * TCP_LIMIT_MM_S  # and it does use what the limit allows


def test_a_safety_function_raises_an_alarm_through_the_units_operator_port() -> None:
    """What a new fault gets without a hook: the safety unit was built with the operator
    state as a port, so an alarm raised through it stops the robot as any alarm does
    (job stopped, servo off, 5001, in the alarm history)."""
    vc = VirtualController()
    assert command(vc, CMD.START_TRAJ_MODE).ok
    operator = vc.safety.operator
    assert operator.state.servo_on
    operator.raise_alarm(4900, 2, "DOOR OPEN")
    operator.servo_off()
    vc.run_ticks(5)
    snap = vc.snapshot()
    assert [(a.code, a.subcode, a.text) for a in snap.alarms] == [(4900, 2, "DOOR OPEN")]
    assert not snap.servo
    assert [a.code for a in operator.state.alarms] == [4900]
    assert vc.alarm_history()[-1].code == 4900
    check = command(vc, CMD.CHECK_MOTION_READY)
    assert check.subcode == NotReadySubcode.ALARM
