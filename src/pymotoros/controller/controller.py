"""The virtual controller: a Yaskawa controller running MotoROS 1.9.12, in virtual time.

:class:`VirtualController` is the composition root of this package and a thin facade:
it implements the protocols of :mod:`pymotoros.controller.api`
(:class:`~pymotoros.controller.api.MotoRosController`, what the servers call;
:class:`~pymotoros.controller.api.OperatorPanel`, the operator's hands; fault injection,
start-up and safety) by delegating to parts that are each testable on their own:

- the MotoROS motion side (:mod:`~pymotoros.controller.commands`,
  :mod:`~pymotoros.controller.trajectory`, run through a
  :class:`~pymotoros.controller.processes.Scheduler`) and its
  :class:`~pymotoros.controller.readiness.Readiness`;
- the IO image with its M-registers and fault injection
  (:mod:`~pymotoros.controller.io_image`) and the operator's forcing
  (:mod:`~pymotoros.controller.forced_io`);
- feedback, status and the per-group snapshot (:mod:`~pymotoros.controller.state_view`);
- the pendant's keys (:mod:`~pymotoros.controller.operator_keys`);
- the safety functions (:mod:`~pymotoros.controller.safety`), brake sag and eco idle
  (:mod:`~pymotoros.controller.drive_power`);
- scenario driving (:mod:`~pymotoros.controller.scenario_player`);
- the tick, in its fixed order (:mod:`~pymotoros.controller.cycle`).

It is pure and deterministic: no sockets, no clock but its own, randomness only from
``seed``. :meth:`VirtualController.tick` advances exactly one interpolation period.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Unpack

from pymotoros.controller import signals
from pymotoros.controller.alarms import Alarm
from pymotoros.controller.api import (
    MOTOROS_OUTPUT_COUNT,
    ControllerSnapshot,
    FeedbackData,
    FiredEventInfo,
    IoRead,
    JobPosition,
    NotReadyInfo,
    Outcome,
    Pending,
    PointData,
    StatusData,
)
from pymotoros.controller.assembly import assemble
from pymotoros.controller.cell import CellConfig, default_cell
from pymotoros.controller.commands import MotionCommands
from pymotoros.controller.connections import ConnectionEvents
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.cycle import TickCycle
from pymotoros.controller.drive_power import DrivePower
from pymotoros.controller.forced_io import ForcedSignals
from pymotoros.controller.incmove_task import IncMoveTask
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.lint import ClientLint, ResumedMotion
from pymotoros.controller.machine import EstopSource, Event, OperatorState
from pymotoros.controller.motoros import MotoRos
from pymotoros.controller.operator_keys import MAX_ALARM_CODE, OperatorKeys
from pymotoros.controller.peripherals import Peripherals
from pymotoros.controller.ports import MotionLink
from pymotoros.controller.processes import Scheduler
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.safety import DEFAULT_RETREAT_MS, PFL_STOP_MS, SafetyUnit
from pymotoros.controller.safety.fsu import FsuRequest
from pymotoros.controller.safety.startup import MotoRosStartup, setup_validation
from pymotoros.controller.scenario import FiredEvent, Scenario, perform
from pymotoros.controller.scenario_player import ScenarioPlayer
from pymotoros.controller.skillsnd import SkillListeners
from pymotoros.controller.state_view import FEEDBACK_FIELDS, StateView
from pymotoros.controller.trajectory import DhTable, TrajectoryPoints
from pymotoros.kinematics.collision import Contact
from pymotoros.models import robot_model
from pymotoros.models.fidelity import Fidelity
from pymotoros.models.workspace import Obstacle
from pymotoros.protocol.constants import IoResultCode, MotionCommand, PendantMode

__all__ = ["FEEDBACK_FIELDS", "MAX_ALARM_CODE", "SnapshotObserver", "VirtualController"]

SnapshotObserver = Callable[[ControllerSnapshot], None]


class VirtualController:
    """A controller running MotoROS: MotoRosController for servers, OperatorPanel for operators."""

    def __init__(
        self,
        cell: CellConfig | None = None,
        *,
        seed: int = 0,
        motion_link: MotionLink | None = None,
    ) -> None:
        """``motion_link``: the motion connections a scenario's ``drop_motion`` closes, given
        by the runtime that serves this controller (``pymotoros.testing``'s twin,
        :meth:`SimulatorApp.for_cell <pymotoros.runtime.app.SimulatorApp.for_cell>`);
        None: no motion server, ``drop_motion`` is refused saying so."""
        self.cell = cell = cell if cell is not None else default_cell()
        self.seed = seed
        parts = assemble(
            cell,
            seed=seed,
            on_skill=lambda slave, text: self._on_skill(slave, text),
            on_operator_change=lambda old, new, event: self._on_operator_change(old, new, event),
        )
        ctx = parts.ctx
        self._ctx = ctx
        self._clock, self._machine, self._io = ctx.clock, ctx.machine, ctx.io
        self._servos = ctx.servos  # the servo models, read by the S1CxG register tests
        self._safety = parts.safety
        self._tcp = parts.tcp
        self._keys = parts.keys
        self._workspace = parts.workspace
        self._motion_link = motion_link
        self.lint = ClientLint()
        """What clients did that a real controller answers differently (issue 31): the
        servers and the tick record it, ``GET /api/lint`` shows it."""
        self._build_motoros(ctx)
        self._forced = ForcedSignals(ctx.io, self._keys)
        self._state = StateView(ctx, self._readiness, self._tcp)
        self._power = DrivePower(ctx, last_motion_ms=lambda: self._inc_move.last_motion_ms)
        self._scenarios = ScenarioPlayer(ctx.io.read_any)
        self._observers: list[SnapshotObserver] = []
        self._readiness.monitor.init_read()
        hc_robot = any(robot_model(r).pfl for r in cell.robots)
        self._startup = MotoRosStartup(
            setup_validation(cell.controller, hc_robot, cell.startup),
            alarms_on=lambda: any(self._io.get(a) for a in signals.ALARM_BITS),
            raise_alarm=self.raise_alarm,
            boot=self._readiness.monitor.init_done,
        )
        self._cycle = TickCycle(
            ctx,
            startup=self._startup,
            safety=self._safety,
            readiness=self._readiness,
            drive_power=self._power,
            inc_move=self._inc_move,
            registers=parts.registers,
            scenarios=self._scenarios,
            peripherals=Peripherals(ctx.io, cell.peripherals),
            scheduler=self._scheduler,
            workspace=self._workspace,
            lint=self.lint,
        )
        # The tick runs every 4 ms for every twin: callers reach the cycle's tick
        # directly, without the facade's call in between (tick() below documents it).
        self.tick = self._cycle.tick  # type: ignore[method-assign]

    def _build_motoros(self, ctx: MotoRosContext) -> None:
        """MotoROS's parts (see motoros.py for their map), all on one context."""
        self._readiness = readiness = Readiness(ctx)
        self._commands = commands = MotionCommands(ctx, readiness)
        self._trajectory = trajectory = TrajectoryPoints(ctx, readiness, commands)
        self._inc_move = inc_move = IncMoveTask(ctx, readiness)
        self._skills = skills = SkillListeners(ctx, readiness)
        self._connections = ConnectionEvents(ctx, inc_move)
        self._motoros = MotoRos(readiness, inc_move, trajectory, skills)
        self._scheduler = Scheduler(ctx.clock)

    # ================================================================== time

    @property
    def period_ms(self) -> int:
        """The interpolation period in ms (4, the generic Yaskawa figure): one ``tick()``."""
        return self._clock.period_ms

    @property
    def time_ms(self) -> int:
        """Controller time since boot, ms."""
        return self._clock.time_ms

    @property
    def tick_count(self) -> int:
        """Interpolation periods run since boot (``time_ms`` is this times ``period_ms``)."""
        return self._clock.tick_count

    @property
    def num_groups(self) -> int:
        """Number of control groups in the cell (robots and external axes), 1 to 4."""
        return self._ctx.num_groups

    def commanded_pulses(self, group_no: int) -> tuple[int, ...]:
        """The group's command register: pulses, controller order, 8 slots.

        The cheap read for per-tick observers (tests that record what the servos
        executed): :meth:`snapshot` converts every group to radians and runs kinematics.
        """
        return self._state.commanded_pulses(group_no)

    @property
    def last_increment_ms(self) -> int:
        """Controller time of the last tick in which IncMove sent increments to the servos
        (zero pulses included: a queue entry was executed); 0 before the first."""
        return self._inc_move.last_motion_ms

    def tick(self) -> None:
        """Advance controller time by exactly one interpolation period (see cycle.py)."""
        self._cycle.tick()

    def run_ticks(self, count: int) -> None:
        """``count`` ticks."""
        tick = self._cycle.tick
        for _ in range(count):
            tick()

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
        """MOTO_MOTION_CTRL: a motion-port command such as CHECK_MOTION_READY or START_TRAJ_MODE;
        its Outcome now, or a Pending that completes on a later tick."""
        return self._scheduler.run(
            self._commands.motion_ctrl(group_no, command),
            lambda: MotionCommand.describe(command),
        )

    def trajectory_point(self, sequence: int, point: PointData) -> Outcome | Pending:
        """JOINT_TRAJ_PT_FULL: one group's trajectory point, accepted (queued) or refused as
        MotoROS does."""
        answer = self._trajectory.trajectory_point(sequence, point)
        if isinstance(answer, Outcome):  # all but a start in ECO mode: no Process
            return answer
        return self._scheduler.run(
            answer, lambda: f"JOINT_TRAJ_PT_FULL sequence {sequence} group {point.group_no}"
        )

    def trajectory_point_ex(self, sequence: int, points: Sequence[PointData]) -> Outcome | Pending:
        """JOINT_TRAJ_PT_FULL_EX: one point for several groups at once, accepted or refused as a
        whole."""
        return self._scheduler.run(
            self._trajectory.trajectory_point_ex(sequence, points),
            lambda: f"JOINT_TRAJ_PT_FULL_EX sequence {sequence}",
        )

    def select_tool(self, group_no: int, tool: int) -> Outcome:
        """SELECT_TOOL (§5.8): the tool number the group's TCP is computed with."""
        return self._trajectory.select_tool(group_no, tool)

    def dh_parameters(self) -> DhTable | None:
        """GET_DH_PARAMETERS (§5.9): per group, the links' (theta, d, a, alpha) in rad and m."""
        return self._trajectory.dh_parameters()

    # ================================================================== IO

    def read_io_bit(self, address: int) -> IoRead:
        """An IO bit as the IO port reads it (MotoROS's address numbering); the IO result code
        MotoROS answers when the address may not be read."""
        return self._io.read_bit(address)

    def write_io_bit(self, address: int, value: int) -> IoResultCode:
        """Write an IO bit as the IO port does (only writable ranges); SUCCESS or the IO result
        code MotoROS answers."""
        return self._io.write_bit(address, value)

    def read_io_group(self, address: int) -> IoRead:
        """An IO group (8 bits, as a byte) as the IO port reads it; the IO result code MotoROS
        answers when the address may not be read."""
        return self._io.read_group(address)

    def write_io_group(self, address: int, value: int) -> IoResultCode:
        """Write an IO group (a byte) as the IO port does; SUCCESS or the IO result code MotoROS
        answers."""
        return self._io.write_group(address, value)

    def read_mregister(self, number: int) -> IoRead:
        """An M-register as the IO port reads it; the IO result code for a number it refuses."""
        return self._io.read_mregister(number)

    def write_mregister(self, number: int, value: int) -> IoResultCode:
        """Write an M-register as the IO port does; SUCCESS or the IO result code MotoROS gives."""
        return self._io.write_mregister(number, value)

    def set_io_api_failure(self, *, reads: bool = False, writes: bool = False) -> None:
        """Fault injection: make client IO reads (1004) and/or writes (1005) fail."""
        self._io.set_api_failure(reads=reads, writes=writes)

    # ================================================================== connections

    def motion_connected(self) -> ResumedMotion | None:
        """A client connected to the motion port: OT#893 (motion connected) on, as
        MotoROS. Not None when the queued increments of a closed motion connection resume
        now (fidelity exact, §2.2), or would on a robot (safe cleared them at the close:
        ``cleared_s``)."""
        return self._connections.motion_connected()

    def motion_disconnected(self) -> None:
        """The IncMove and AddToIncQueue tasks end; the queues are kept and resumed by
        the next motion connection (exact, as MotoROS 1.9.12, §2.2) or cleared (safe)."""
        self._connections.motion_disconnected()

    @property
    def fidelity(self) -> Fidelity:
        """exact or safe: the cell's ``[motoros] fidelity`` (docs/fidelity.md)."""
        return self.cell.fidelity

    def state_clients_changed(self, count: int) -> None:
        """The number of state-port clients changed: OT#894 is on while there is at least one."""
        self.lint.state_clients = count
        self._connections.state_clients_changed(count)

    def io_connected(self) -> None:
        """A client connected to the IO port: sets OT#895 (MotoROS never clears it)."""
        self._connections.io_connected()

    def has_queued_motion(self) -> bool:
        """Whether any group still has increments queued (the robot is still to move)."""
        return self._ctx.queues.has_queued_motion()

    # ================================================================== state server

    def joint_feedback(self, group_no: int) -> FeedbackData:
        """§2.4: feedback pulses → rad (m), ROS order; speed from the servo model."""
        return self._state.joint_feedback(group_no)

    def in_motion(self) -> bool:
        """Any queue holds increments, or |feedback − command| > 30 pulses on a valid axis."""
        return self._state.in_motion()

    def robot_status(self) -> StatusData:
        """§2.6, from the status monitor's last reading."""
        return self._state.robot_status()

    def snapshot(self) -> ControllerSnapshot:
        """An immutable picture of the controller now (what ``GET /api/state`` and the pendant
        show)."""
        return ControllerSnapshot(
            time_ms=self._clock.time_ms,
            tick_count=self._clock.tick_count,
            operator=self._keys.snapshot(),
            motion_ready=self._readiness.monitor.outlook(),
            groups=self._state.group_snapshots(),
            safety=self._safety.snapshot(),
            motoros=self._startup.phase,
            workspace=self._workspace.snapshot(),
            events=tuple(
                FiredEventInfo(f.t, f.action, tuple(f.params.items()), f.error)
                for f in self._scenarios.fired
            ),
            # what only a pendant shows
            period_ms=self._clock.period_ms,
            not_ready=NotReadyInfo(*self._motoros.not_ready_reason()),
            jobs=tuple(JobPosition(job, line) for job, line in self._ctx.runner.position()),
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
        """The IO image (inputs, outputs, registers): the operator's and the cell's side of IO."""
        return self._io

    @property
    def job_position(self) -> tuple[tuple[str, int], ...]:
        """(job, line) of every running job task; empty when no job runs."""
        return self._ctx.runner.position()

    def alarm_history(self) -> tuple[Alarm, ...]:
        """Alarms and errors raised so far, oldest first (bounded: the oldest drop out)."""
        return self._keys.alarm_history()

    def alarms_raised(self) -> int:
        """Every alarm raised since boot, counted as it is raised (the alarm history keeps
        only the last 100, so a counter derived from it would miss alarms between scrapes)."""
        return self._keys.alarms_raised()

    def subscribe(self, observer: SnapshotObserver) -> None:
        """``observer(snapshot)`` after every operator-state change."""
        self._observers.append(observer)

    # ================================================================== operator panel

    def press_estop(self, pressed: bool, source: EstopSource = EstopSource.PENDANT) -> None:
        """E-stop: cuts servo power and stops the job; raises no alarm."""
        self._keys.press_estop(pressed, source)

    def set_hold(self, on: bool) -> None:
        """The HOLD key, on (True) or off: HOLD stops the job (and so MotoROS's motion); off
        leaves it stopped."""
        self._keys.set_hold(on)

    def set_mode(self, mode: PendantMode) -> None:
        """The pendant's mode key (TEACH or PLAY); MotoROS moves only in PLAY."""
        self._keys.set_mode(mode)

    def set_remote(self, on: bool) -> None:
        """The REMOTE key: MotoROS moves only in REMOTE."""
        self._keys.set_remote(on)

    def set_servo(self, on: bool) -> None:
        """Servo power request as from the pendant (refused silently while E-stopped or alarmed)."""
        self._keys.set_servo(on)

    def set_eco(self, on: bool) -> None:
        """Enter eco mode (servo power saved; needs servo on) or leave it (servo power back)."""
        self._keys.set_eco(on)

    def raise_alarm(self, code: int, subcode: int, text: str) -> None:
        """Raise a controller alarm (code 0..9999): the job stops, servo power goes off if the
        alarm's class cuts it, and motion is refused until the alarm is reset."""
        self._keys.raise_alarm(code, subcode, text)

    def raise_error(self, code: int, subcode: int = 0, text: str = "") -> None:
        """An operator error (50014): refuses motion with 5002 until reset; not an alarm."""
        self._keys.raise_error(code, subcode, text)

    def reset(self) -> None:
        """The pendant's RESET key: clears alarms and errors (their causes are gone)."""
        self._keys.reset()

    def force_io(self, address: int, value: int) -> None:
        """Force a bit or an M-register (1000000 + n) as the operator simulating the cell.

        Signals that belong to the operator state (E-stop inputs, mode, remote, servo,
        hold, eco, operating, alarm and error outputs) are forced through the same
        transition as the matching key, so the state stays consistent.
        """
        self._forced.force(address, value)

    # ================================================================== scenarios

    def load_scenario(self, scenario: Scenario) -> None:
        """Run ``scenario``'s events from the next tick (replacing events not fired yet)."""
        self._scenarios.load(scenario, lambda event: perform(self, event), self.time_ms)

    @property
    def fired_events(self) -> tuple[FiredEvent, ...]:
        """Scenario events fired so far (time since boot, action, parameters, refusal)."""
        return self._scenarios.fired

    def drop_motion(self) -> None:
        """Close the motion connection as a pulled cable (a scenario's ``drop_motion``)."""
        if self._motion_link is None:
            raise ValueError(
                "drop_motion: no motion server is attached to this controller (a controller "
                "built with motion_link=None; SimulatorApp.for_cell and pymotoros.testing "
                "build it with one)"
            )
        self._motion_link.drop_clients()

    # ================================================================== safety functions

    @property
    def motoros_started(self) -> bool:
        """MotoROS passed its start-up checks: INIT_DONE is on, its servers may listen."""
        return self._startup.started

    @property
    def motoros_phase(self) -> str:
        """Where MotoROS's start-up is: "running", waiting (for what), or halted (why)."""
        return self._startup.phase

    @property
    def keys(self) -> OperatorKeys:
        """The pendant's keys (the operator state's part), for the declared actions."""
        return self._keys

    @property
    def safety(self) -> SafetyUnit:
        """The cell's safety functions (PFL, FSU), for the control API and tests."""
        return self._safety

    @property
    def workspace_contacts(self) -> tuple[Contact, ...]:
        """What the robot touched at the latest workspace check (empty: nothing, or a cell
        without obstacles)."""
        contact = self._workspace.contact
        return contact.contacts if contact is not None else ()

    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        """The cell's obstacles now (the cell file's, then as put and removed)."""
        return self._workspace.obstacles

    def put_obstacle(self, entry: Mapping[str, object]) -> Obstacle:
        """Add an obstacle or move the one of that name (the cell file's keys; a bad one
        is a ConfigError naming its key). The contact check follows from the next tick."""
        return self._workspace.put(entry)

    def remove_obstacle(self, name: str) -> None:
        """Remove the obstacle ``name`` (ConfigError when there is none)."""
        self._workspace.remove(name)

    def workspace_state(self) -> dict[str, object]:
        """``{"obstacles": [...], "contacts": [...]}``: the state document's workspace."""
        return self._workspace.state()

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

    def set_fsu(self, **request: Unpack[FsuRequest]) -> None:
        """Switch the FSU speed limits at run time (ValueError for a bad request)."""
        self._safety.fsu.set(**request)

    # ================================================================== internals

    def _on_skill(self, slave: int, text: str) -> None:
        self._skills.on_skill(slave, text)

    def _on_operator_change(self, old: OperatorState, new: OperatorState, event: Event) -> None:
        if old.drives_powered and not new.drives_powered:
            self._power.brakes_engage()
        if new.job_running and not old.job_running:
            self._ctx.runner.start()
        elif old.job_running and not new.job_running:
            self._ctx.runner.stop()
            self._skills.on_job_stopped()
        if self._observers:
            snap = self.snapshot()
            for observer in self._observers:
                observer(snap)
