"""The virtual controller: a Yaskawa controller running MotoROS 1.9.12, in virtual time.

:class:`VirtualController` composes the pieces of this package and implements both
protocols of :mod:`pymotoros.controller.api`: :class:`~pymotoros.controller.api.MotoRosController`
(what the servers call) and :class:`~pymotoros.controller.api.OperatorPanel` (the
operator's hands). It is pure and deterministic: no sockets, no clock but its own,
randomness only from ``seed``. :meth:`VirtualController.tick` advances exactly one
interpolation period; in one tick, in this order:

1. timed operator events (servo power coming on, leaving eco mode);
2. the INFORM job (every task as far as it goes);
3. the MotoROS status monitor, on its 10 ms boundaries;
4. the IncMove task (one increment per group to the servos);
5. the AddToIncQueue tasks (interpolation into the queues);
6. commands that were waiting (START_TRAJ_MODE polls …), whose Pending completes here.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.alarms import Alarm, AlarmClass, AlarmHistory
from pymotoros.controller.api import (
    MOTOROS_OUTPUT_COUNT,
    ControllerSnapshot,
    FeedbackData,
    FiredEventInfo,
    GroupSnapshot,
    IoRead,
    JobPosition,
    NotReadyInfo,
    Outcome,
    PendantMode,
    Pending,
    PointData,
    StatusData,
)
from pymotoros.controller.cell import CellConfig, default_cell
from pymotoros.controller.commands import MotionCommands
from pymotoros.controller.connections import ConnectionEvents
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.incmove_task import IncMoveTask
from pymotoros.controller.inform import JobRunner, builtin_jobs, load_jobs
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.machine import (
    EstopSource,
    Event,
    OperatorMachine,
    OperatorState,
    ServoPower,
)
from pymotoros.controller.motoros import MotoRos
from pymotoros.controller.peripherals import Peripherals
from pymotoros.controller.processes import ControllerClock, Scheduler
from pymotoros.controller.queues import MotionQueues
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.registers import RegisterOutputs
from pymotoros.controller.safety import DEFAULT_RETREAT_MS, PFL_STOP_MS, SafetyUnit
from pymotoros.controller.safety.startup import MotoRosStartup, setup_validation
from pymotoros.controller.scenario import FiredEvent, Scenario, ScenarioDriver, perform
from pymotoros.controller.servo import IN_MOTION_PULSES, ServoGroup
from pymotoros.controller.skillsnd import SkillListeners
from pymotoros.controller.tcp import TcpTracker
from pymotoros.controller.trajectory import DhTable, TrajectoryPoints
from pymotoros.controller.units import RosConverter
from pymotoros.models import robot_model
from pymotoros.models.controllers import M_REGISTER_BASE
from pymotoros.motion import GroupAxes, GroupInterpolator, to_pulses
from pymotoros.protocol.constants import (
    MAX_JOINTS,
    IoResultCode,
    MotionCommand,
    StatusMode,
    ValidFields,
)

logger = logging.getLogger(__name__)

FEEDBACK_FIELDS: Final = int(ValidFields.POSITION | ValidFields.VELOCITY)
"""JOINT_FEEDBACK validFields: position and velocity, never time (§2.4)."""
MAX_ALARM_CODE: Final = 9999

# Alarm numbers used when the operator forces an alarm output on (no alarm text exists).
_FORCED_ALARM_CODE: Final = {
    AlarmClass.MAJOR: 0,
    AlarmClass.MINOR: 4000,
    AlarmClass.USER: 8000,
    AlarmClass.SYSTEM: 9000,
}

SnapshotObserver = Callable[[ControllerSnapshot], None]


def _why_no_pfl(cell: CellConfig) -> str:
    """Why a cell has no PFL function ("" when it has one)."""
    if cell.pfl:
        return ""
    if not cell.controller.pfl_signals:
        return f"the {cell.controller.type.value} has no PFL (only YRC1000 / YRC1000micro)"
    if not any(robot_model(r).pfl for r in cell.robots):
        return f"{', '.join(cell.robots)} is not an HC (collaborative) robot"
    return "the cell's PFL option is off (controller.pfl = false)"


def _pad(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(values) + (0.0,) * (MAX_JOINTS - len(values))


class VirtualController:
    """A controller running MotoROS: MotoRosController for servers, OperatorPanel for operators."""

    def __init__(self, cell: CellConfig | None = None, *, seed: int = 0) -> None:
        self.cell = cell = cell if cell is not None else default_cell()
        self.seed = seed
        ctrl = cell.controller
        self._clock = ControllerClock(ctrl.interpolation_period_ms)
        self._io = IoImage(ctrl)
        init = cell.initial
        state = OperatorState(
            mode=init.mode,
            remote=init.remote,
            servo=ServoPower.ON if init.servo else ServoPower.OFF,
            estop=frozenset({EstopSource.PENDANT}) if init.estop else frozenset(),
            hold=init.hold,
            eco=init.eco,
            alarms=tuple(Alarm(a.code, a.subcode, a.text, 0) for a in init.alarms),
        )
        self._history = AlarmHistory()
        for alarm in state.alarms:
            self._history.record(alarm)
        self._machine = OperatorMachine(
            state, self._io, servo_on_delay_ms=cell.servo.servo_on_delay_ms
        )
        variant = cell.job_variant
        if variant is not None:
            jobs = builtin_jobs(variant)
        else:
            jobs = load_jobs(cell.jobs if isinstance(cell.jobs, tuple) else ())
        self._runner = JobRunner(jobs, self._io, on_skill=self._on_skill)
        self._axes = tuple(GroupAxes.from_model(g, ctrl) for g in cell.groups)
        self._interps = tuple(GroupInterpolator(a) for a in self._axes)
        for interp, tool in zip(self._interps, init.tools, strict=False):
            interp.tool = tool
        self._to_ros = tuple(RosConverter(a) for a in self._axes)
        self._tcp = TcpTracker(cell)
        self._registers = RegisterOutputs(cell, self._io, self._tcp, ctrl.interpolation_period_ms)
        self._servos = tuple(
            ServoGroup(
                to_pulses(init.joints[g] if init.joints else (), axes),
                period_ms=ctrl.interpolation_period_ms,
                lag_ticks=cell.servo.lag_ticks,
                noise_pulses=cell.servo.noise_pulses,
                seed=seed,
                group_index=g,
            )
            for g, axes in enumerate(self._axes)
        )
        self._safety = safety = SafetyUnit(
            self._io,
            self._axes,
            self._servos,
            period_ms=ctrl.interpolation_period_ms,
            pfl_enabled=cell.pfl,
            pfl_why_disabled=_why_no_pfl(cell),
            fsu_boot_pct=cell.servo.fsu_speed_limit_pct,
        )
        # MotoROS (see motoros.py for the map of its parts)
        self._queues = queues = MotionQueues(self._interps)
        ctx = MotoRosContext(
            cell=cell,
            clock=self._clock,
            io=self._io,
            machine=self._machine,
            runner=self._runner,
            queues=queues,
            axes=self._axes,
            interpolators=self._interps,
            servos=self._servos,
            increment_clip=safety.fsu.limits,
            increment_tcp_clip=safety.fsu.tcp_clip,
        )
        safety.fsu.tcp_limiter = self._tcp_limiter
        self._readiness = readiness = Readiness(ctx)
        self._commands = commands = MotionCommands(ctx, readiness)
        self._trajectory = trajectory = TrajectoryPoints(ctx, readiness, commands)
        self._inc_move = inc_move = IncMoveTask(ctx, readiness)
        self._skills = skills = SkillListeners(ctx, readiness)
        self._connections = ConnectionEvents(ctx)
        self._motoros = MotoRos(readiness, inc_move, trajectory, skills)
        self._scheduler = Scheduler(self._clock)
        self._observers: list[SnapshotObserver] = []
        self._power_losses = 0
        self._eco_idle_ms = None if cell.servo.eco_idle_s is None else cell.servo.eco_idle_s * 1000
        self._machine.add_observer(self._on_operator_change)
        readiness.init_read()
        self._startup = MotoRosStartup(
            setup_validation(ctrl, any(robot_model(r).pfl for r in cell.robots), cell.startup),
            alarms_on=lambda: any(self._io.get(a) for a in signals.ALARM_BITS),
            raise_alarm=self.raise_alarm,
            boot=readiness.init_done,
        )
        self._starting = not self._startup.settled
        self._peripherals = Peripherals(self._io, cell.peripherals)
        self._has_peripherals = self._peripherals.active
        self._pfl = safety.pfl
        self._scenario: ScenarioDriver | None = None
        self._fired: list[FiredEvent] = []
        self.drop_motion_hook: Callable[[], None] | None = None
        """Closes the motion connection (set by the runtime; a scenario's drop_motion)."""

    # ================================================================== time

    @property
    def period_ms(self) -> int:
        return self._clock.period_ms

    @property
    def time_ms(self) -> int:
        """Controller time since boot, ms."""
        return self._clock.time_ms

    @property
    def tick_count(self) -> int:
        return self._clock.tick_count

    @property
    def num_groups(self) -> int:
        return len(self._axes)

    def commanded_pulses(self, group_no: int) -> tuple[int, ...]:
        """The group's command register: pulses, controller order, 8 slots.

        The cheap read for per-tick observers (tests that record what the servos
        executed): :meth:`snapshot` converts every group to radians and runs kinematics.
        """
        self._check_group(group_no)
        return tuple(self._servos[group_no].command)

    @property
    def last_increment_ms(self) -> int:
        """Controller time of the last tick in which IncMove sent increments to the servos
        (zero pulses included: a queue entry was executed); 0 before the first."""
        return self._inc_move.last_motion_ms

    def tick(self) -> None:
        """Advance controller time by exactly one interpolation period."""
        clock = self._clock
        clock.tick_count += 1
        now = clock.time_ms = clock.time_ms + clock.period_ms
        machine = self._machine
        timer = machine.next_timer_ms
        if timer is not None and now >= timer:
            machine.advance(now)
        if self._starting:
            self._startup.tick(now)
            self._starting = not self._startup.settled
        safety_moved = self._pfl.phase != "idle" and self._safety.tick(now)
        runner = self._runner
        if (now >= runner.wake_ms or self._io.changes != runner.seen_changes) and runner.step(now):
            machine.fire(Event.END_JOB, now)
        readiness = self._readiness
        if now >= readiness.next_monitor_ms:
            readiness.monitor_tick(now)
            if self._eco_idle_ms is not None:
                self._check_eco_idle(now, self._eco_idle_ms)
        inc_move = self._inc_move
        moved = inc_move.inc_move_tick()
        if not moved and not safety_moved:
            for servo in self._servos:
                servo.idle()
        inc_move.fill_tick()
        if self._registers.active:  # S1CxG register outputs: only when configured
            self._registers.refresh(
                self._servos,
                [i.tool for i in self._interps],
                clock.tick_count,
                machine.state.drives_powered,
            )
        if self._scenario is not None:
            self._scenario.tick(now, moved)
        if self._has_peripherals:
            self._peripherals.tick(now)
        scheduler = self._scheduler
        if scheduler.busy:
            scheduler.advance()

    def run_ticks(self, count: int) -> None:
        """``count`` ticks."""
        for _ in range(count):
            self.tick()

    def wait_for(self, result: Outcome | Pending, *, max_ticks: int = 5000) -> Outcome:
        """Tick until ``result`` is complete and return its Outcome (plain-loop helper).

        Raises ``TimeoutError`` after ``max_ticks`` ticks: a command that never completes
        is a bug, not a refusal.
        """
        if isinstance(result, Outcome):
            return result
        for _ in range(max_ticks):
            if result.done:
                return result.outcome
            self.tick()
        if result.done:
            return result.outcome
        raise TimeoutError(f"{result.description} did not complete within {max_ticks} ticks")

    # ================================================================== motion port

    def motion_ctrl(self, group_no: int, command: int) -> Outcome | Pending:
        return self._scheduler.run(
            self._commands.motion_ctrl(group_no, command),
            lambda: MotionCommand.describe(command),
        )

    def trajectory_point(self, sequence: int, point: PointData) -> Outcome | Pending:
        now = self._trajectory.trajectory_point_now(sequence, point)
        if now is not None:  # the streaming hot path: answered without a Process
            return now
        return self._scheduler.run(
            self._trajectory.trajectory_point(sequence, point),
            lambda: f"JOINT_TRAJ_PT_FULL sequence {sequence} group {point.group_no}",
        )

    def trajectory_point_ex(self, sequence: int, points: Sequence[PointData]) -> Outcome | Pending:
        return self._scheduler.run(
            self._trajectory.trajectory_point_ex(sequence, points),
            lambda: f"JOINT_TRAJ_PT_FULL_EX sequence {sequence}",
        )

    def select_tool(self, group_no: int, tool: int) -> Outcome:
        return self._trajectory.select_tool(group_no, tool)

    def dh_parameters(self) -> DhTable | None:
        return self._trajectory.dh_parameters()

    # ================================================================== IO

    def read_io_bit(self, address: int) -> IoRead:
        return self._io.read_bit(address)

    def write_io_bit(self, address: int, value: int) -> IoResultCode:
        return self._io.write_bit(address, value)

    def read_io_group(self, address: int) -> IoRead:
        return self._io.read_group(address)

    def write_io_group(self, address: int, value: int) -> IoResultCode:
        return self._io.write_group(address, value)

    def read_mregister(self, number: int) -> IoRead:
        return self._io.read_mregister(number)

    def write_mregister(self, number: int, value: int) -> IoResultCode:
        return self._io.write_mregister(number, value)

    def set_io_api_failure(self, *, reads: bool = False, writes: bool = False) -> None:
        """Fault injection: make client IO reads (1004) and/or writes (1005) fail."""
        self._io.fail_reads = reads
        self._io.fail_writes = writes

    # ================================================================== connections

    def motion_connected(self) -> None:
        self._connections.motion_connected()

    def motion_disconnected(self) -> None:
        """Clears the queues: our documented improvement over MotoROS (§2.2)."""
        self._connections.motion_disconnected()

    def state_clients_changed(self, count: int) -> None:
        self._connections.state_clients_changed(count)

    def io_connected(self) -> None:
        self._connections.io_connected()

    def has_queued_motion(self) -> bool:
        return self._queues.has_queued_motion()

    # ================================================================== state server

    def _check_group(self, group_no: int) -> None:
        if not 0 <= group_no < len(self._axes):
            raise ValueError(f"group {group_no} does not exist (0..{len(self._axes) - 1})")

    def joint_feedback(self, group_no: int) -> FeedbackData:
        """§2.4: feedback pulses → rad (m), ROS order; speed from the servo model."""
        self._check_group(group_no)
        servo = self._servos[group_no]
        pulses = servo.feedback(self._clock.tick_count, self._machine.state.drives_powered)
        to_ros = self._to_ros[group_no]
        return FeedbackData(
            group_no, FEEDBACK_FIELDS, _pad(to_ros(pulses)), _pad(to_ros(servo.speed()))
        )

    def in_motion(self) -> bool:
        """Any queue holds increments, or |feedback − command| > 30 pulses on a valid axis."""
        if self._queues.has_queued_motion():
            return True
        powered = self._machine.state.drives_powered
        tick = self._clock.tick_count
        for axes, servo in zip(self._axes, self._servos, strict=True):
            if servo.settled():  # feedback = command (± noise of at most 10 pulses)
                continue
            fb = servo.feedback(tick, powered)
            cmd = servo.command
            for slot, valid in enumerate(axes.valid):
                if valid and abs(fb[slot] - cmd[slot]) > IN_MOTION_PULSES:
                    return True
        return False

    def robot_status(self) -> StatusData:
        """§2.6, from the status monitor's last reading."""
        mr = self._readiness
        servo, eco = mr.servo_reading
        return StatusData(
            drives_powered=int(servo and not eco),
            e_stopped=int(mr.estopped),
            error_code=mr.error_code,
            in_error=int(mr.in_error),
            in_motion=int(self.in_motion()),
            mode=int(StatusMode.encode(mr.play_reading)),
            motion_possible=int(mr.motion_ready),
        )

    def snapshot(self) -> ControllerSnapshot:
        s = self._machine.state
        tick = self._clock.tick_count
        groups = []
        for g, (axes, servo, interp) in enumerate(
            zip(self._axes, self._servos, self._interps, strict=True)
        ):
            n = axes.num_axes
            cmd = servo.command
            command_rad = self._to_ros[g](cmd)[:n]
            feedback_rad = self._to_ros[g](servo.feedback(tick, s.drives_powered))[:n]
            groups.append(
                GroupSnapshot(
                    name=self.cell.groups[g].name,
                    joint_names=axes.joint_names,
                    command_rad=command_rad,
                    feedback_rad=feedback_rad,
                    command_pulse=tuple(cmd[axes.ros_to_slot[i]] for i in range(n)),
                    queue=len(interp.queue),
                    tool=interp.tool,
                    tcp=self._tcp.snapshot(
                        g,
                        interp.tool,
                        command_rad,
                        feedback_rad,
                        [
                            v * 1000.0 / self._clock.period_ms
                            for v in self._to_ros[g](servo.last_increment)[:n]
                        ],
                        self._to_ros[g](servo.speed())[:n],
                    ),
                )
            )
        return ControllerSnapshot(
            time_ms=self._clock.time_ms,
            tick_count=tick,
            mode=s.mode,
            remote=s.remote,
            servo=s.servo_on,
            estop=s.estopped,
            hold=s.hold,
            alarms=tuple(a.info for a in s.alarms),
            motion_ready=self._readiness.outlook(),
            groups=tuple(groups),
            errors=tuple(e.info for e in s.errors),
            fsu_joint_speed_pct=self._safety.fsu.active.joint_speed_pct,
            fsu_tcp_speed_mm_s=self._safety.fsu.active.tcp_speed_mm_s,
            pfl=self._safety.pfl.status.phase if self._safety.pfl.enabled else "off",
            motoros=self._startup.phase,
            events=tuple(
                FiredEventInfo(f.t, f.action, tuple(f.params.items()), f.error)
                for f in self._fired
            ),
            # what only a pendant shows
            period_ms=self._clock.period_ms,
            eco=s.eco,
            not_ready=NotReadyInfo(*self._motoros.not_ready_reason()),
            jobs=tuple(JobPosition(job, line) for job, line in self._runner.position()),
            motoros_outputs=self._motoros_outputs(),
            cell=self.cell,
        )

    def _motoros_outputs(self) -> tuple[int, ...]:
        """OT#889..896, one IO group (addresses n×10+0..7): one read, not eight."""
        byte = self._io.read_group(signals.ROS_READY // 10).value
        return tuple((byte >> i) & 1 for i in range(MOTOROS_OUTPUT_COUNT))

    @property
    def operator_state(self) -> OperatorState:
        """The pendant's view, frozen."""
        return self._machine.state

    @property
    def motoros(self) -> MotoRos:
        """MotoROS's flags (motion_ready, job_ready, inc_move_error …) for tests and pendant."""
        return self._motoros

    @property
    def io(self) -> IoImage:
        return self._io

    @property
    def job_position(self) -> tuple[tuple[str, int], ...]:
        """(job, line) of every running job task; empty when no job runs."""
        return self._runner.position()

    def alarm_history(self) -> tuple[Alarm, ...]:
        return self._history.entries()

    def subscribe(self, observer: SnapshotObserver) -> None:
        """``observer(snapshot)`` after every operator-state change."""
        self._observers.append(observer)

    # ================================================================== operator panel

    def _fire(
        self, event: Event, *, alarm: Alarm | None = None, source: EstopSource = EstopSource.PENDANT
    ) -> str | None:
        return self._machine.fire(event, self._clock.time_ms, alarm=alarm, source=source)

    def press_estop(self, pressed: bool, source: EstopSource = EstopSource.PENDANT) -> None:
        """E-stop: cuts servo power and stops the job; raises no alarm."""
        self._fire(Event.PRESS_ESTOP if pressed else Event.RELEASE_ESTOP, source=source)

    def set_hold(self, on: bool) -> None:
        self._fire(Event.HOLD_ON if on else Event.HOLD_OFF)

    def set_mode(self, mode: PendantMode) -> None:
        if not isinstance(mode, PendantMode):
            raise ValueError(f"mode must be a PendantMode, not {mode!r}")
        self._fire(Event.SELECT_PLAY if mode is PendantMode.PLAY else Event.SELECT_TEACH)

    def set_remote(self, on: bool) -> None:
        self._fire(Event.REMOTE_ON if on else Event.REMOTE_OFF)

    def set_servo(self, on: bool) -> None:
        """Servo power request as from the pendant (refused silently while E-stopped or alarmed)."""
        refused = self._fire(Event.REQUEST_SERVO_ON if on else Event.SERVO_OFF)
        if refused:
            logger.info("servo on refused: %s", refused)

    def set_eco(self, on: bool) -> None:
        """Enter eco mode (servo power saved; needs servo on) or leave it (servo power back)."""
        if on:
            refused = self._fire(Event.ENTER_ECO)
            if refused:
                logger.info("eco mode refused: %s", refused)
        else:
            self._fire(Event.WAKE_FROM_ECO)

    def raise_alarm(self, code: int, subcode: int, text: str) -> None:
        if not 0 <= code <= MAX_ALARM_CODE:
            raise ValueError(f"alarm code {code} is outside 0..{MAX_ALARM_CODE}")
        alarm = Alarm(code, subcode, text, self._clock.time_ms)
        self._history.record(alarm)
        self._fire(Event.RAISE_ALARM, alarm=alarm)

    def raise_error(self, code: int, subcode: int = 0, text: str = "") -> None:
        """An operator error (50014): refuses motion with 5002 until reset; not an alarm."""
        if not 0 <= code <= MAX_ALARM_CODE:
            raise ValueError(f"error code {code} is outside 0..{MAX_ALARM_CODE}")
        error = Alarm(code, subcode, text, self._clock.time_ms)
        self._history.record(error)
        self._fire(Event.RAISE_ERROR, alarm=error)

    def reset(self) -> None:
        """The pendant's RESET key: clears alarms and errors (their causes are gone)."""
        self._fire(Event.RESET_ALARMS)
        self._fire(Event.CANCEL_ERRORS)

    def force_io(self, address: int, value: int) -> None:
        """Force a bit or an M-register (1000000 + n) as the operator simulating the cell.

        Signals that belong to the operator state (E-stop inputs, mode, remote, servo,
        hold, eco, operating, alarm and error outputs) are forced through the same
        transition as the matching key, so the state stays consistent.
        """
        self._io.check_forcible(address, value)
        if address >= M_REGISTER_BASE:
            self._io.set_mregister(address - M_REGISTER_BASE, value)
            return
        on = bool(value)
        handler = self._forced_signal_handlers().get(address)
        if handler is not None:
            handler(on)
        else:
            self._io.set(address, on)

    def _forced_signal_handlers(self) -> dict[int, Callable[[bool], None]]:
        def estop(source: EstopSource) -> Callable[[bool], None]:
            return lambda on: self.press_estop(not on, source)

        def alarm_output(cls: AlarmClass) -> Callable[[bool], None]:
            def force(on: bool) -> None:
                if on:
                    code = _FORCED_ALARM_CODE[cls]
                    self.raise_alarm(code, 0, f"{cls.name.lower()} alarm forced on {cls.address}")
                else:
                    self._fire(Event.RESET_ALARMS)

            return force

        def operating(on: bool) -> None:
            refused = self._fire(Event.START_JOB if on else Event.STOP_JOB)
            if refused:
                raise ValueError(f"cannot start the job: {refused}")

        handlers: dict[int, Callable[[bool], None]] = {
            signals.ESTOP_EXTERNAL: estop(EstopSource.EXTERNAL),
            signals.ESTOP_PENDANT: estop(EstopSource.PENDANT),
            signals.ESTOP_CONTROLLER: estop(EstopSource.CONTROLLER),
            signals.REMOTE: self.set_remote,
            signals.PLAY: lambda on: self.set_mode(PendantMode.PLAY if on else PendantMode.TEACH),
            signals.TEACH: lambda on: self.set_mode(PendantMode.TEACH if on else PendantMode.PLAY),
            signals.HOLD: self.set_hold,
            signals.SERVO_ON: self.set_servo,
            signals.ECO_MODE: self.set_eco,
            signals.OPERATING: operating,
            signals.ERROR: self._force_error,
        }
        for cls in AlarmClass:
            handlers[cls.address] = alarm_output(cls)
        return handlers

    # ================================================================== scenarios

    def load_scenario(self, scenario: Scenario) -> None:
        """Run ``scenario``'s events from the next tick (replacing events not fired yet)."""
        driver = ScenarioDriver(
            scenario,
            perform=lambda event: perform(self, event),
            read_io=self._read_any_io,
            now_ms=self.time_ms,
        )
        driver.fired = self._fired
        self._scenario = driver
        logger.info("scenario %s: %d events", scenario.source, len(scenario.events))

    @property
    def fired_events(self) -> tuple[FiredEvent, ...]:
        """Scenario events fired so far (time since boot, action, parameters, refusal)."""
        return tuple(self._fired)

    def _read_any_io(self, address: int) -> int:
        if address >= M_REGISTER_BASE:
            return self._io.read_mregister(address - M_REGISTER_BASE).value
        return self._io.get(address)

    def drop_motion(self) -> None:
        """Close the motion connection as a pulled cable (a scenario's ``drop_motion``)."""
        if self.drop_motion_hook is None:
            raise ValueError("drop_motion: no motion server is attached to this controller")
        self.drop_motion_hook()

    # ================================================================== safety functions

    def _tcp_limiter(
        self, limit_mm_s: float, group: int, command: Sequence[int], increment: Sequence[int]
    ) -> tuple[int, ...]:
        """The FSU's TCP-speed clip: scale the tick's increment so the TCP of the active
        tool moves at most ``limit_mm_s`` (rounded down per axis, so never above it); a
        group without a kinematic chain is not clipped."""
        speed = self._tcp.increment_speed_mm_s(
            group, self._interps[group].tool, command, increment
        )
        scale = 1.0 if speed <= limit_mm_s else limit_mm_s / speed
        return tuple(int(abs(p) * scale) for p in increment)

    @property
    def motoros_started(self) -> bool:
        """MotoROS passed its start-up checks: INIT_DONE is on, its servers may listen."""
        return self._startup.started

    @property
    def motoros_phase(self) -> str:
        """Where MotoROS's start-up is: "running", waiting (for what), or halted (why)."""
        return self._startup.phase

    @property
    def safety(self) -> SafetyUnit:
        """The cell's safety functions (PFL, FSU), for the control API and tests."""
        return self._safety

    def pfl_event(
        self, event: str, *, retreat_ms: int = DEFAULT_RETREAT_MS, stop_ms: int = PFL_STOP_MS
    ) -> None:
        """A PFL contact or clamping now (ValueError when the cell cannot have one)."""
        self._safety.pfl.event(
            event,
            self._clock.time_ms,
            moving=self.in_motion(),
            stop_ms=stop_ms,
            retreat_ms=retreat_ms if event == "clamping" else 0,
        )

    def set_fsu(
        self,
        *,
        joint_speed_pct: int | None = None,
        tcp_speed_mm_s: float | None = None,
        off: bool = False,
    ) -> None:
        """Switch the FSU speed limits at run time (ValueError for a bad request)."""
        self._safety.fsu.set(
            joint_speed_pct=joint_speed_pct, tcp_speed_mm_s=tcp_speed_mm_s, off=off
        )

    def _force_error(self, on: bool) -> None:
        if on:
            self.raise_error(0, 0, "error forced on 50014")
        else:
            self._fire(Event.CANCEL_ERRORS)

    # ================================================================== internals

    def _brakes_engage(self) -> None:
        sag = self.cell.servo.brake_sag_pulses
        self._power_losses += 1
        if not sag:
            return
        for servo, axes in zip(self._servos, self._axes, strict=True):
            servo.shift(servo.sag_offsets(sag, self._power_losses, axes.valid))

    def _check_eco_idle(self, now: int, idle_ms: int) -> None:
        """Eco mode after the configured idle time with servo on (checked every 10 ms)."""
        s = self._machine.state
        if not s.servo_on or s.eco:
            return
        if now - self._inc_move.last_motion_ms >= idle_ms and now - s.servo_ready_at_ms >= idle_ms:
            logger.info("eco mode: no motion for %d s", idle_ms // 1000)
            self._fire(Event.ENTER_ECO)

    def _on_skill(self, slave: int, text: str) -> None:
        self._skills.on_skill(slave, text)

    def _on_operator_change(self, old: OperatorState, new: OperatorState, event: Event) -> None:
        if old.drives_powered and not new.drives_powered:
            self._brakes_engage()
        if new.job_running and not old.job_running:
            self._runner.start()
        elif old.job_running and not new.job_running:
            self._runner.stop()
            self._skills.on_job_stopped()
        if self._observers:
            snap = self.snapshot()
            for observer in self._observers:
                observer(snap)
