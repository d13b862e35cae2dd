"""The parts VirtualController composes, each on its own (no facade in between)."""

from __future__ import annotations

import pytest

from pymotoros.controller import PendantMode, cell_from_dict, default_cell, signals
from pymotoros.controller.alarms import AlarmClass
from pymotoros.controller.assembly import assemble, initial_operator_state, why_no_pfl
from pymotoros.controller.cell import InitialState
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.cycle import TickCycle
from pymotoros.controller.drive_power import DrivePower
from pymotoros.controller.forced_io import FORCED_ALARM_CODE, ForcedSignals
from pymotoros.controller.incmove_task import IncMoveTask
from pymotoros.controller.machine import EstopSource, Event
from pymotoros.controller.operator_keys import OperatorKeys
from pymotoros.controller.peripherals import Peripherals
from pymotoros.controller.processes import Scheduler
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.replies import invalid
from pymotoros.controller.safety.startup import MotoRosStartup
from pymotoros.controller.scenario import ScenarioEvent, parse_scenario
from pymotoros.controller.scenario_player import ScenarioPlayer
from pymotoros.controller.state_view import FEEDBACK_FIELDS, StateView
from pymotoros.controller.tool_point import TcpTracker
from pymotoros.models.controllers import M_REGISTER_BASE
from pymotoros.protocol.constants import InvalidSubcode, IoResultCode, ResultCode


def _ctx(cell_data: dict[str, object] | None = None) -> MotoRosContext:
    cell = default_cell() if cell_data is None else cell_from_dict(cell_data)
    return assemble(cell, seed=0, on_skill=lambda slave, text: None).ctx


def _keys(ctx: MotoRosContext) -> OperatorKeys:
    return OperatorKeys(ctx.machine, ctx.clock)


# ------------------------------------------------------------------ assembly


def test_assembly_builds_one_context_for_every_group() -> None:
    ctx = _ctx({"groups": [{"robot": "gp7"}, {"robot": "gp7"}]})
    assert ctx.num_groups == 2
    assert len(ctx.interpolators) == len(ctx.servos) == len(ctx.queues.interpolators) == 2
    assert ctx.queues.interpolators == ctx.interpolators


def test_the_initial_operator_state_is_the_cell_files() -> None:
    state = initial_operator_state(InitialState(servo=True, estop=True, hold=True))
    assert state.estop == frozenset({EstopSource.PENDANT})
    assert state.hold
    assert state.mode is PendantMode.PLAY


def test_why_no_pfl_names_the_missing_part() -> None:
    assert why_no_pfl(default_cell("yrc1000", "hc10")) == ""
    assert "no PFL" in why_no_pfl(default_cell("dx200", "hc10"))
    assert "not an HC" in why_no_pfl(default_cell("yrc1000", "gp7"))


# ------------------------------------------------------------------ OperatorKeys


def test_keys_fire_their_events_and_keep_the_alarm_history() -> None:
    ctx = _ctx()
    keys = _keys(ctx)
    keys.set_hold(True)
    assert ctx.machine.state.hold
    keys.raise_alarm(4100, 1, "minor")
    keys.raise_error(20, 0, "operator error")
    assert [a.code for a in keys.alarm_history()] == [4100, 20]
    keys.reset()
    assert not ctx.machine.state.alarms
    assert not ctx.machine.state.errors
    assert len(keys.alarm_history()) == 2  # the history keeps what was reset


def test_keys_refuse_what_no_pendant_could_send() -> None:
    keys = _keys(_ctx())
    with pytest.raises(ValueError, match=r"alarm code 10000 is outside 0\.\.9999"):
        keys.raise_alarm(10000, 0, "")
    with pytest.raises(ValueError, match="error code -1 is outside"):
        keys.raise_error(-1)
    with pytest.raises(ValueError, match="must be a PendantMode"):
        keys.set_mode("play")  # type: ignore[arg-type]


def test_an_alarm_at_boot_is_in_the_history() -> None:
    ctx = _ctx({"initial": {"alarms": [{"code": 4100, "text": "at boot"}]}})
    assert [a.code for a in _keys(ctx).alarm_history()] == [4100]


# ------------------------------------------------------------------ ForcedSignals


def test_forcing_an_estop_input_low_presses_that_estop() -> None:
    ctx = _ctx()
    forced = ForcedSignals(ctx.io, _keys(ctx))
    forced.force(signals.ESTOP_EXTERNAL, 0)
    assert ctx.machine.state.estop == frozenset({EstopSource.EXTERNAL})
    forced.force(signals.ESTOP_EXTERNAL, 1)
    assert not ctx.machine.state.estopped


def test_forcing_an_alarm_output_raises_an_alarm_of_that_class() -> None:
    ctx = _ctx()
    forced = ForcedSignals(ctx.io, _keys(ctx))
    forced.force(signals.ALARM_MINOR, 1)
    codes = [a.code for a in ctx.machine.state.alarms]
    assert codes == [FORCED_ALARM_CODE[AlarmClass.MINOR]]
    forced.force(signals.ALARM_MINOR, 0)
    assert not ctx.machine.state.alarms


def test_other_signals_and_m_registers_are_written_directly() -> None:
    ctx = _ctx()
    forced = ForcedSignals(ctx.io, _keys(ctx))
    forced.force(10010, 1)
    forced.force(M_REGISTER_BASE + 7, 1234)
    assert ctx.io.get(10010) == 1
    assert ctx.io.read_any(M_REGISTER_BASE + 7) == 1234


def test_forcing_refuses_what_cannot_be_forced() -> None:
    ctx = _ctx()
    forced = ForcedSignals(ctx.io, _keys(ctx))
    with pytest.raises(ValueError, match="takes 0 or 1"):
        forced.force(10010, 2)
    forced.force(signals.SERVO_ON, 0)
    ctx.machine.fire(Event.PRESS_ESTOP, 0)
    with pytest.raises(ValueError, match="cannot start the job"):
        forced.force(signals.OPERATING, 1)


# ------------------------------------------------------------------ StateView


def test_the_state_view_checks_the_group_number() -> None:
    ctx = _ctx()
    view = StateView(ctx, Readiness(ctx), TcpTracker(ctx.cell))
    with pytest.raises(ValueError, match=r"group 1 does not exist \(0..0\)"):
        view.joint_feedback(1)
    assert len(view.commanded_pulses(0)) == 8


def test_the_state_view_reads_a_robot_at_rest() -> None:
    ctx = _ctx({"initial": {"joints": {"R1": [0.1, 0.0, 0.0, 0.0, 0.0, 0.0]}}})
    readiness = Readiness(ctx)
    readiness.monitor.init_read()
    view = StateView(ctx, readiness, TcpTracker(ctx.cell))
    fb = view.joint_feedback(0)
    assert fb.valid_fields == FEEDBACK_FIELDS
    assert fb.pos[0] == pytest.approx(0.1, abs=1e-4)
    assert not view.in_motion()
    status = view.robot_status()
    assert (status.drives_powered, status.in_motion, status.motion_possible) == (0, 0, 0)
    (group,) = view.group_snapshots()
    assert group.command_rad[0] == pytest.approx(0.1, abs=1e-4)
    assert group.tcp is not None
    assert group.tcp.command_speed_mm_s == 0.0


# ------------------------------------------------------------------ DrivePower


def test_each_power_loss_sags_the_axes_by_the_configured_pulses() -> None:
    ctx = _ctx({"controller": {"brake_sag_pulses": 200}})
    power = DrivePower(ctx, last_motion_ms=lambda: 0)
    before = tuple(ctx.servos[0].command)
    power.brakes_engage()
    assert power.power_losses == 1
    assert tuple(ctx.servos[0].command) != before


def test_no_sag_without_brake_sag_pulses() -> None:
    ctx = _ctx()
    power = DrivePower(ctx, last_motion_ms=lambda: 0)
    before = tuple(ctx.servos[0].command)
    power.brakes_engage()
    assert tuple(ctx.servos[0].command) == before
    assert power.power_losses == 1


def test_eco_mode_after_the_idle_time_with_servo_on() -> None:
    ctx = _ctx({"controller": {"eco_idle_s": 1}, "initial": {"servo": True}})
    power = DrivePower(ctx, last_motion_ms=lambda: 0)
    assert power.eco_idle_ms == 1000
    power.check_eco_idle(990)
    assert not ctx.machine.state.eco
    power.check_eco_idle(1000)
    assert ctx.machine.state.eco
    assert DrivePower(_ctx(), last_motion_ms=lambda: 0).eco_idle_ms is None


# ------------------------------------------------------------------ ScenarioPlayer


def test_the_player_fires_due_events_and_keeps_the_record_across_loads() -> None:
    performed: list[str] = []

    def perform(event: ScenarioEvent) -> None:
        performed.append(event.action)

    player = ScenarioPlayer(read_io=lambda address: 0)
    player.tick(4, False)  # nothing loaded: nothing happens
    scenario = parse_scenario({"events": [{"at": 0.008, "action": "hold", "on": True}]})
    player.load(scenario, perform, now_ms=0)
    player.tick(4, False)
    assert performed == []
    player.tick(8, False)
    assert performed == ["hold"]
    player.load(parse_scenario({"events": [{"at": 0.0, "action": "reset"}]}), perform, 8)
    player.tick(12, False)
    assert [f.action for f in player.fired] == ["hold", "reset"]


# ------------------------------------------------------------------ TickCycle


def test_one_tick_runs_every_part_once_in_order() -> None:
    parts = assemble(default_cell(), seed=0, on_skill=lambda slave, text: None)
    ctx = parts.ctx
    readiness = Readiness(ctx)
    readiness.monitor.init_read()
    startup = MotoRosStartup(
        None, alarms_on=lambda: False, raise_alarm=lambda *a: None, boot=lambda: None
    )
    scenarios = ScenarioPlayer(ctx.io.read_any)
    scenarios.load(
        parse_scenario({"events": [{"at": 0.004, "action": "hold", "on": True}]}),
        lambda event: ctx.io.set(10010, 1),
        now_ms=0,
    )
    cycle = TickCycle(
        ctx,
        startup=startup,
        safety=parts.safety,
        readiness=readiness,
        drive_power=DrivePower(ctx, last_motion_ms=lambda: 0),
        inc_move=IncMoveTask(ctx, readiness),
        registers=parts.registers,
        scenarios=scenarios,
        peripherals=Peripherals(ctx.io, ctx.cell.peripherals),
        scheduler=Scheduler(ctx.clock),
    )
    ctx.io.set(signals.HOLD, 1)
    cycle.tick()
    period = ctx.clock.period_ms
    assert (ctx.clock.time_ms, ctx.clock.tick_count) == (period, 1)
    assert readiness.reading.hold == 1  # the monitor ran on its first boundary
    assert readiness.monitor.next_monitor_ms == 10
    assert ctx.io.get(10010) == 1  # the scenario's event fired after the motion tasks
    assert [f.action for f in scenarios.fired] == ["hold"]


# ------------------------------------------------------------------ small helpers


def test_io_image_reads_any_address_and_fails_on_request() -> None:
    io = _ctx().io
    io.set_api_failure(reads=True, writes=False)
    assert io.read_bit(10010).result_code is IoResultCode.READ_API_ERROR
    assert io.write_bit(10010, 1) is IoResultCode.OK
    assert io.read_any(10010) == 1  # the operator's view never fails
    io.set_api_failure(reads=False, writes=True)
    assert io.write_mregister(1, 5) is IoResultCode.WRITE_API_ERROR
    assert io.read_mregister(1).value == 0


def test_the_tcp_clip_keeps_the_tool_within_the_limit() -> None:
    cell = default_cell()
    tcp = TcpTracker(cell)
    command = [0] * 8
    increment = [2000, 2000, 2000, 0, 0, 0, 0, 0]
    speed = tcp.increment_speed_mm_s(0, 0, command, increment)
    assert speed > 0
    clipped = tcp.clip_increment(speed / 2, 0, 0, command, increment)
    assert tcp.increment_speed_mm_s(0, 0, command, clipped) <= speed / 2
    assert tcp.clip_increment(speed * 2, 0, 0, command, increment) == tuple(increment)
    negative = [-p for p in increment]
    assert tcp.clip_increment(speed * 2, 0, 0, command, negative) == tuple(increment)


def test_invalid_is_a_3000_reply_with_its_subcode() -> None:
    outcome = invalid(InvalidSubcode.SEQUENCE, "sequence -1 is negative", 0)
    assert outcome.result is ResultCode.INVALID
    assert outcome.subcode == InvalidSubcode.SEQUENCE
    assert (outcome.group_no, outcome.detail) == (0, "sequence -1 is negative")
