"""The parts of Readiness, each on its own: the flags, the status monitor, the NOT_READY reasons."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import pytest

from pymotoros.controller import cell_from_dict, default_cell, signals
from pymotoros.controller.alarms import Alarm
from pymotoros.controller.assembly import assemble
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.machine import Event
from pymotoros.controller.not_ready import NotReadyReasons
from pymotoros.controller.ready_flags import Latches, ReadyFlags
from pymotoros.controller.status_monitor import StatusMonitor
from pymotoros.controller.status_reading import BOOT_READING, StatusReading
from pymotoros.protocol.constants import NotReadySubcode as Nr
from pymotoros.protocol.constants import ResultCode

READY = BOOT_READING._replace(play=1, remote=1, operating=1, servo=1, ros_ready=1)
"""A reading in which nothing holds the robot."""

Change = Callable[[ReadyFlags], None]


def _flags(*, pfl: bool = False, dx100: bool = False, groups: int = 1) -> ReadyFlags:
    return ReadyFlags(pfl_option=pfl, dx100=dx100, num_groups=groups)


def _ready_flags(*, pfl: bool = False, dx100: bool = False, groups: int = 1) -> ReadyFlags:
    flags = _flags(pfl=pfl, dx100=dx100, groups=groups)
    _see(flags, READY)
    return flags


def _see(flags: ReadyFlags, reading: StatusReading, *, job_ready: bool = True) -> None:
    """A status monitor run that read ``reading`` (no PFL event)."""
    flags.observe(reading, job_ready=job_ready, pfl_event=False)


def _ctx(cell_data: dict[str, object] | None = None) -> MotoRosContext:
    cell = default_cell() if cell_data is None else cell_from_dict(cell_data)
    return assemble(cell, seed=0, on_skill=lambda slave, text: None).ctx


# ------------------------------------------------------------------ StatusReading


def test_a_reading_says_what_it_means() -> None:
    assert not BOOT_READING.estopped
    assert not BOOT_READING.in_error
    assert BOOT_READING._replace(estop_ok=(1, 0, 1)).estopped
    assert BOOT_READING._replace(alarm_bits=(0, 0, 1, 0)).in_error
    assert not BOOT_READING._replace(error=1).in_error  # an operator error is not an alarm
    assert BOOT_READING._replace(pfl=(1, 0, 0, 0, 0)).pfl_active
    assert not BOOT_READING._replace(pfl=(0, 0, 1, 0, 0)).pfl_active  # avoiding, no direction
    assert BOOT_READING._replace(pfl=(0, 0, 1, 0, 1)).pfl_active


# ------------------------------------------------------------------ ReadyFlags


def test_flags_start_not_ready_and_follow_the_monitors_reading() -> None:
    flags = _flags()
    assert not flags.motion_ready
    assert flags.latches == Latches()
    flags.observe(READY, job_ready=True, pfl_event=False)
    assert flags.motion_ready
    assert flags.reading is READY
    flags.observe(READY._replace(remote=0), job_ready=True, pfl_event=False)
    assert not flags.motion_ready


@pytest.mark.parametrize(
    ("latch", "clear"),
    [
        (lambda f: f.latch_inc_move_error("refused"), lambda f: f.clear_inc_move_error()),
        (lambda f: f.begin_stop(), lambda f: f.end_stop()),
        (lambda f: f.forget_job_ready(), lambda f: _see(f, READY)),
        (lambda f: f.latch_inc_move_error("refused"), lambda f: f.clear_latches()),
    ],
)
def test_every_latch_changes_motion_ready_at_once(latch: Change, clear: Change) -> None:
    flags = _ready_flags()
    latch(flags)
    assert not flags.motion_ready
    clear(flags)
    assert flags.motion_ready


def test_the_pfl_latch_counts_only_with_the_pfl_option() -> None:
    without = _ready_flags()
    without.latch_pfl_event()
    assert without.motion_ready
    assert not without.pfl_active
    with_pfl = _ready_flags(pfl=True)
    with_pfl.latch_pfl_event()
    assert not with_pfl.motion_ready
    assert with_pfl.pfl_active
    with_pfl.clear_pfl_latch()
    assert with_pfl.motion_ready


def test_the_latches_are_one_read_only_value() -> None:
    flags = _ready_flags()
    flags.latch_inc_move_error("an incremental move was refused: -1")
    latches = flags.latches
    assert latches.inc_move_error
    assert latches.inc_move_error_reason.endswith("-1")
    with pytest.raises(AttributeError):
        latches.inc_move_error = False  # type: ignore[misc]
    with pytest.raises(AttributeError):
        flags.motion_ready = True  # type: ignore[misc]


def test_a_dx100_waits_for_the_skill_flag_of_each_slave() -> None:
    flags = _ready_flags(dx100=True, groups=2)
    assert not flags.motion_ready
    assert flags.missing_skills() == (1, 2)
    flags.set_skill_flag(1, True)
    assert not flags.motion_ready
    assert flags.missing_skills() == (2,)
    flags.set_skill_flag(2, True)
    assert flags.motion_ready
    assert flags.missing_skills() == ()
    flags.clear_skill_flags()
    assert not flags.motion_ready
    assert _ready_flags(groups=2).missing_skills() == ()  # not a DX100: no skill flags


def test_ready_for_answers_without_changing_anything() -> None:
    flags = _ready_flags(pfl=True)
    assert not flags.ready_for(True, 1, 1, False, (1, 0, 0, 0, 0))
    assert not flags.ready_for(True, 1, 1, True, (0, 0, 0, 0, 0))
    assert not flags.ready_for(False, 1, 1, False, (0, 0, 0, 0, 0))
    assert flags.motion_ready


# ------------------------------------------------------------------ StatusMonitor


def test_the_monitor_runs_on_its_10ms_boundaries_and_only_when_a_signal_changed() -> None:
    ctx = _ctx()
    flags = _flags()
    monitor = StatusMonitor(ctx, flags)
    monitor.init_read()
    first = flags.reading
    assert monitor.next_monitor_ms == 0
    monitor.monitor_tick(4)
    assert monitor.next_monitor_ms == 10
    ctx.io.set(signals.HOLD, 1)
    monitor.monitor_tick(8)  # not a boundary yet
    assert flags.reading == first
    monitor.monitor_tick(12)
    assert flags.reading.hold == 1
    assert monitor.next_monitor_ms == 20
    assert not ctx.io.monitor_dirty


def test_the_outlook_sees_the_signals_before_the_monitor_does() -> None:
    ctx = _ctx()
    flags = _flags()
    monitor = StatusMonitor(ctx, flags)
    monitor.init_read()
    for address in (signals.PLAY, signals.REMOTE, signals.OPERATING, signals.ROS_READY):
        ctx.io.set(address, 1)
    assert monitor.outlook()
    assert not flags.motion_ready
    monitor.status_update()
    assert flags.motion_ready
    assert flags.latches.job_ready


class _RecordingQueues:
    """Stands in for MotionQueues: always holds motion, counts the clears."""

    def __init__(self) -> None:
        self.clears = 0

    def has_queued_motion(self) -> bool:
        return True

    def any_pending(self) -> bool:
        return False

    def clear(self) -> None:
        self.clears += 1


@pytest.mark.parametrize(
    ("change", "clears"),
    [
        ((signals.ROS_READY, 0), 1),  # OT#889 fell
        ((signals.ALARM_MINOR, 1), 1),  # an alarm came on
        ((signals.REMOTE, 0), 1),  # remote lost
        ((signals.HOLD, 1), 0),  # HOLD alone does not clear (the job stops, OPERATING falls)
        ((10010, 1), 0),  # a signal the monitor does not read
    ],
)
def test_the_monitor_clears_the_queues_on_its_edges(change: tuple[int, int], clears: int) -> None:
    queues = _RecordingQueues()
    ctx = dataclasses.replace(_ctx(), queues=queues)  # type: ignore[arg-type]
    flags = _flags()
    monitor = StatusMonitor(ctx, flags)
    monitor.init_read()
    for address in (signals.PLAY, signals.REMOTE, signals.OPERATING, signals.SERVO_ON):
        ctx.io.set(address, 1)
    ctx.io.set(signals.ROS_READY, 1)
    monitor.status_update()
    assert flags.motion_ready
    queues.clears = 0
    ctx.io.set(*change)
    monitor.status_update()
    assert queues.clears == clears


def test_an_alarm_edge_sets_the_error_code_to_the_first_alarm() -> None:
    ctx = _ctx()
    monitor = StatusMonitor(ctx, _flags())
    monitor.init_read()
    ctx.machine.fire(Event.RAISE_ALARM, 0, alarm=Alarm(4100, 2, "minor", 0))
    monitor.status_update()
    assert monitor.error_code == 4100
    ctx.machine.fire(Event.RESET_ALARMS, 0)
    monitor.status_update()
    assert monitor.error_code == 0


def test_init_done_raises_init_done_and_the_connect_server_output() -> None:
    ctx = _ctx()
    monitor = StatusMonitor(ctx, _flags())
    monitor.init_done()
    assert ctx.io.get(signals.INIT_DONE) == 1
    assert ctx.io.get(signals.CONNECT_SERVER_RUNNING) == 1


# ------------------------------------------------------------------ NotReadyReasons


def test_the_first_failing_test_of_the_4_2_order_wins() -> None:
    ctx = _ctx()
    flags = _flags()
    reasons = NotReadyReasons(ctx, flags)
    _see(flags, BOOT_READING._replace(alarm_bits=(1, 0, 0, 0), hold=1), job_ready=False)
    assert reasons.subcode() is Nr.ALARM
    flags.observe(READY._replace(hold=1), job_ready=True, pfl_event=False)
    assert reasons.subcode() is Nr.HOLD
    flags.observe(READY._replace(servo=1, eco=1), job_ready=True, pfl_event=False)
    assert reasons.subcode() is Nr.SERVO_OFF
    assert reasons.specifics(Nr.SERVO_OFF) == "eco mode"
    assert reasons.why(Nr.SERVO_OFF) == f"eco mode; {Nr.SERVO_OFF.remedy}"
    flags.observe(READY, job_ready=True, pfl_event=False)
    assert reasons.subcode() is Nr.UNSPECIFIED
    assert reasons.why(Nr.UNSPECIFIED) == ""


def test_the_refusal_names_the_subcode_and_what_clears_it() -> None:
    ctx = _ctx()
    flags = _ready_flags()
    reasons = NotReadyReasons(ctx, flags)
    flags.latch_inc_move_error("an incremental move was refused: -3")
    outcome = reasons.outcome(ResultCode.FALSE, group_no=0)
    assert outcome.result is ResultCode.FALSE
    assert outcome.subcode == Nr.INC_MOVE_ERROR
    assert outcome.group_no == 0
    remedy = Nr.INC_MOVE_ERROR.remedy
    assert outcome.detail.endswith(f"(an incremental move was refused: -3; {remedy})")


def test_the_skillsend_detail_lists_every_missing_condition() -> None:
    ctx = _ctx({"controller": {"model": "dx100"}, "robot": {"model": "sia20d"}})
    flags = _flags(dx100=True)
    reasons = NotReadyReasons(ctx, flags)
    flags.observe(READY, job_ready=False, pfl_event=False)
    flags.begin_stop()
    assert reasons.subcode() is Nr.SKILLSEND
    assert reasons.specifics(Nr.SKILLSEND) == (
        'SKILLSND "ROS-START" not received for slave 1; '
        "OT#889 is on but its rising edge was not seen; a stop is in progress"
    )

