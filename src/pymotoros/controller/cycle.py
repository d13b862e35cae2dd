"""One interpolation period of the virtual controller, in the order the real one runs it.

:meth:`TickCycle.tick` advances the controller clock by exactly one period; in one
tick, in this order:

1. timed operator events (servo power coming on, leaving eco mode) and MotoROS's
   start-up checks;
2. a PFL stop or retreat under way (the safety unit moves the servos itself);
3. the INFORM job (every task as far as it goes);
4. the MotoROS status monitor on its 10 ms boundaries, and the eco-mode idle timer;
5. the IncMove task (one increment per group to the servos), idle servos otherwise;
   the workspace contact check of the new commanded position (only in a cell with
   obstacles);
6. the AddToIncQueue tasks (interpolation into the queues), then the client lint's
   queue-starved check (only while a group's last accepted point moves);
7. the outputs that follow the servos (S1CxG registers: what they read is kept here,
   their words are computed when an M-register is read), the scenario's events, the
   simulated peripherals;
8. commands that were waiting (START_TRAJ_MODE polls …), whose Pending completes here.
"""

from __future__ import annotations

from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.drive_power import DrivePower
from pymotoros.controller.incmove_task import IncMoveTask
from pymotoros.controller.lint import ClientLint
from pymotoros.controller.machine import Event
from pymotoros.controller.peripherals import Peripherals
from pymotoros.controller.processes import Scheduler
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.registers import RegisterOutputs
from pymotoros.controller.safety import SafetyUnit
from pymotoros.controller.safety.startup import MotoRosStartup
from pymotoros.controller.scenario_player import ScenarioPlayer
from pymotoros.controller.workspace_runtime import WorkspaceRuntime


class TickCycle:
    """The fixed order of one tick over the parts of one controller."""

    def __init__(
        self,
        ctx: MotoRosContext,
        *,
        startup: MotoRosStartup,
        safety: SafetyUnit,
        readiness: Readiness,
        drive_power: DrivePower,
        inc_move: IncMoveTask,
        registers: RegisterOutputs,
        scenarios: ScenarioPlayer,
        peripherals: Peripherals,
        scheduler: Scheduler,
        workspace: WorkspaceRuntime | None = None,
        lint: ClientLint | None = None,
    ) -> None:
        self._ctx = ctx
        self._startup = startup
        self._starting = not startup.settled
        self._safety = safety
        self._monitor = readiness.monitor
        self._drive_power = drive_power
        self._inc_move = inc_move
        self._registers = registers
        self._has_registers = registers.active
        self._scenarios = scenarios
        self._peripherals = peripherals
        self._has_peripherals = peripherals.active
        self._scheduler = scheduler
        self._workspace = workspace
        """The cell's obstacles and their contact check (None, or its ``contact`` None:
        nothing to touch, nothing to do)."""
        self._lint = lint if lint is not None else ClientLint()
        """Where the queue-starved check reports (the controller's client lint)."""

    def tick(self) -> None:
        """Advance controller time by exactly one interpolation period.

        Written out in one piece (each step guarded by a cheap test) because it runs
        every 4 ms for every twin: a call per step would cost more than most steps.
        """
        ctx = self._ctx
        clock = ctx.clock
        clock.tick_count += 1
        now = clock.time_ms = clock.time_ms + clock.period_ms
        machine = ctx.machine
        timer = machine.next_timer_ms
        if timer is not None and now >= timer:
            machine.advance(now)
        if self._starting:
            self._startup.tick(now)
            self._starting = not self._startup.settled
        safety_moved = self._safety.pfl.phase != "idle" and self._safety.tick(now)
        runner = ctx.runner
        if (now >= runner.wake_ms or ctx.io.changes != runner.seen_changes) and runner.step(now):
            machine.fire(Event.END_JOB, now)
        monitor = self._monitor
        if now >= monitor.next_monitor_ms:
            monitor.monitor_tick(now)
            if self._drive_power.eco_idle_ms is not None:
                self._drive_power.check_eco_idle(now)
        inc_move = self._inc_move
        moved = inc_move.inc_move_tick()
        if not moved and not safety_moved:
            for servo in ctx.servos:
                servo.idle()
        elif (workspace := self._workspace) is not None and workspace.contact is not None:
            workspace.contact.tick(now)
        inc_move.fill_tick()
        if moved and self._lint.watching_queues:  # queue-starved: only after a moving point
            self._starved(now)
        if self._has_registers:  # S1CxG register outputs: only when configured
            self._registers.step(
                ctx.servos, ctx.interpolators, clock.tick_count, machine.state.drives_powered
            )
        if self._scenarios.loaded:
            self._scenarios.tick(now, moved)
        if self._has_peripherals:
            self._peripherals.tick(now)
        scheduler = self._scheduler
        if scheduler.busy:
            scheduler.advance()

    def _starved(self, now_ms: int) -> None:
        """Report each group whose queue IncMove just emptied while its last point moved
        (client lint, issue 31): nothing pending, nothing queued, the robot stops dead."""
        interps = self._ctx.interpolators
        for group in self._lint.moving_groups():
            if group < len(interps):
                interp = interps[group]
                if not interp.pending and not len(interp.queue):
                    self._lint.queue_ran_empty(group, now_ms / 1000.0)
