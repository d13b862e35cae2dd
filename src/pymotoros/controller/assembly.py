"""How a cell becomes a controller's parts: the construction steps of the virtual controller.

:class:`~pymotoros.controller.controller.VirtualController` is the composition root;
the functions here build what it composes from a :class:`~pymotoros.controller.cell.CellConfig`
(operator state, jobs, servos, the pendant's keys, the kinematics, the safety unit, the
workspace, the shared :class:`MotoRosContext`), so each step reads on its own and tests
can build one part without the whole controller. Parts are wired here and only here:
each receives what it acts on as a constructor argument (the ports of
:mod:`pymotoros.controller.ports`), and no part is plugged into another afterwards.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from pymotoros.controller.alarms import Alarm
from pymotoros.controller.cell import CellConfig, InitialState
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.inform import Job, JobRunner, builtin_jobs, load_jobs
from pymotoros.controller.io_image import IoImage, mregister_words
from pymotoros.controller.machine import (
    EstopSource,
    Observer,
    OperatorMachine,
    OperatorState,
    ServoPower,
)
from pymotoros.controller.operator_keys import OperatorKeys
from pymotoros.controller.processes import ControllerClock
from pymotoros.controller.queues import MotionQueues
from pymotoros.controller.registers import RegisterOutputs
from pymotoros.controller.safety import SafetyUnit
from pymotoros.controller.safety.fsu import IncrementLimiter
from pymotoros.controller.safety.pfl import retreat_record_ticks
from pymotoros.controller.servo import ServoGroup
from pymotoros.controller.tool_point import TcpTracker
from pymotoros.controller.workspace_runtime import WorkspaceRuntime
from pymotoros.models import robot_model
from pymotoros.motion import GroupAxes, GroupInterpolator, to_pulses


def initial_operator_state(init: InitialState) -> OperatorState:
    """The operator state the cell file asks for at boot."""
    return OperatorState(
        mode=init.mode,
        remote=init.remote,
        servo=ServoPower.ON if init.servo else ServoPower.OFF,
        estop=frozenset({EstopSource.PENDANT}) if init.estop else frozenset(),
        hold=init.hold,
        eco=init.eco,
        alarms=tuple(Alarm(a.code, a.subcode, a.text, 0) for a in init.alarms),
    )


def cell_jobs(cell: CellConfig) -> dict[str, Job]:
    """The built-in INIT_ROS variant the cell names, or the job files it lists."""
    if cell.job_variant is not None:
        return builtin_jobs(cell.job_variant)
    return load_jobs(cell.jobs if isinstance(cell.jobs, tuple) else ())


def servo_groups(
    cell: CellConfig, axes: tuple[GroupAxes, ...], seed: int
) -> tuple[ServoGroup, ...]:
    """One servo model per group, at the cell's initial joints."""
    init = cell.initial
    return tuple(
        ServoGroup(
            to_pulses(init.joints[g] if init.joints else (), group_axes),
            period_ms=cell.controller.interpolation_period_ms,
            lag_ticks=cell.servo.lag_ticks,
            noise_pulses=cell.servo.noise_pulses,
            seed=seed,
            group_index=g,
            record_ticks=retreat_record_ticks(cell.controller.interpolation_period_ms)
            if cell.pfl
            else 0,
        )
        for g, group_axes in enumerate(axes)
    )


def why_no_pfl(cell: CellConfig) -> str:
    """Why a cell has no PFL function ("" when it has one)."""
    if cell.pfl:
        return ""
    if not cell.controller.pfl_signals:
        return f"the {cell.controller.type.value} has no PFL (only YRC1000 / YRC1000micro)"
    if not any(robot_model(r).pfl for r in cell.robots):
        return f"{', '.join(cell.robots)} is not an HC (collaborative) robot"
    return "the cell's PFL option is off (controller.pfl = false)"


def tcp_limiter(tcp: TcpTracker, interps: Sequence[GroupInterpolator]) -> IncrementLimiter:
    """The FSU's TCP-speed port: the kinematics clip a tick's increment with the group's
    selected tool."""

    def limit(
        limit_mm_s: float, group: int, command: Sequence[int], increment: Sequence[int]
    ) -> Sequence[int]:
        return tcp.clip_increment(limit_mm_s, group, interps[group].tool, command, increment)

    return limit


@dataclass(frozen=True, slots=True)
class Assembly:
    """The shared parts of one controller, wired: its safety unit, the pendant's keys
    (also the safety unit's :class:`~pymotoros.controller.ports.OperatorPort`), the
    kinematics of the tool point, the S1CxG register outputs (sharing the IO image's
    M-registers) and the workspace with its contact check."""

    ctx: MotoRosContext
    safety: SafetyUnit
    keys: OperatorKeys
    tcp: TcpTracker
    registers: RegisterOutputs
    workspace: WorkspaceRuntime


def assemble(
    cell: CellConfig,
    *,
    seed: int,
    on_skill: Callable[[int, str], None],
    on_operator_change: Observer | None = None,
) -> Assembly:
    """Build the clock, IO image, operator machine, job runner, groups, the pendant's
    keys, the kinematics, the safety unit and the workspace, each given what it acts on
    (``on_skill``: a DX100 SKILLSND; ``on_operator_change``: the controller's reaction to
    an operator-state change)."""
    ctrl = cell.controller
    clock = ControllerClock(ctrl.interpolation_period_ms)
    tcp = TcpTracker(cell)
    # The register outputs write M-registers only when one is read or written: the
    # image is built with them as the step it takes before any M-register access.
    mregisters = mregister_words()
    registers = RegisterOutputs(cell, mregisters, tcp, ctrl.interpolation_period_ms)
    io = IoImage(
        ctrl,
        mregisters=mregisters,
        before_mregister_access=registers.materialise if registers.active else None,
    )
    machine = OperatorMachine(
        initial_operator_state(cell.initial),
        io,
        servo_on_delay_ms=cell.servo.servo_on_delay_ms,
        observer=on_operator_change,
    )
    runner = JobRunner(cell_jobs(cell), io, on_skill=on_skill)
    axes = tuple(GroupAxes.from_model(g, ctrl) for g in cell.groups)
    interps = tuple(GroupInterpolator(a) for a in axes)
    for interp, tool in zip(interps, cell.initial.tools, strict=False):
        interp.tool = tool
    servos = servo_groups(cell, axes, seed)
    keys = OperatorKeys(machine, clock)
    safety = SafetyUnit(
        io,
        axes,
        servos,
        operator=keys,
        tcp_limiter=tcp_limiter(tcp, interps),
        period_ms=ctrl.interpolation_period_ms,
        pfl_enabled=cell.pfl,
        pfl_why_disabled=why_no_pfl(cell),
        fsu_boot_pct=cell.servo.fsu_speed_limit_pct,
    )
    ctx = MotoRosContext(
        cell=cell,
        clock=clock,
        io=io,
        machine=machine,
        runner=runner,
        queues=MotionQueues(interps),
        axes=axes,
        interpolators=interps,
        servos=servos,
        increment_clip=safety.fsu.limits,
        increment_tcp_clip=safety.fsu.tcp_clip,
    )
    workspace = WorkspaceRuntime(ctx, safety.pfl, safety.operator)
    return Assembly(ctx, safety, keys, tcp, registers, workspace)
