"""Cell configuration: which controller, which robot(s), tools, and the state at boot.

A cell is described by one TOML file (format in ``docs/cell.md``, example in
``examples/cells/``); without a file, :func:`default_cell` gives the embedded
HC10 on a YRC1000. Every mistake in a file raises :class:`~pymotoros.errors.ConfigError`
whose message names the key (``groups[1].robot``, ``initial.joints.R1``) and the problem.

Any robot may be combined with any controller. Combinations that are not sold are
allowed and reported in :attr:`CellConfig.warnings` (and logged), as are groups beyond
what MotoROS supports on that controller, which it ignores (reference §2.1).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Final

from pymotoros.controller.inform import BUILTIN_VARIANTS, JobRunner, load_jobs
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.peripherals import MAX_DELAY_MS
from pymotoros.controller.safety.startup import check_parameters
from pymotoros.controller.values import (
    FEEDBACK_LAG_TICKS,
    SERVO_ON_DELAY_MS,
    AlarmInfo,
    CellConfig,
    InitialState,
    PeripheralConfig,
    ServoConfig,
    StartupConfig,
    ToolConfig,
)
from pymotoros.errors import ConfigError, JobError
from pymotoros.models import (
    DEFAULT_CONTROLLER,
    DEFAULT_ROBOT,
    ControllerModel,
    ControllerType,
    GroupKind,
    GroupModel,
    controller_model,
    robot_model,
)
from pymotoros.models.cell import (
    CellFile,
    GroupPart,
    cell_file_from_dict,
    read_cell_file,
)
from pymotoros.models.fidelity import DEFAULT_FIDELITY, Fidelity
from pymotoros.models.s1cxg import S1cxgTable, parse_s1cxg
from pymotoros.models.toml_file import TomlTable
from pymotoros.models.workspace import ToolShape, parse_tool_shape
from pymotoros.protocol.constants import MAX_TOOL_NUMBER, PendantMode

__all__ = [
    "FEEDBACK_LAG_TICKS",
    "MAX_BRAKE_SAG_PULSES",
    "MAX_NOISE_PULSES",
    "SERVO_ON_DELAY_MS",
    "CellConfig",
    "InitialState",
    "ServoConfig",
    "ToolConfig",
    "cell_from_dict",
    "cell_from_file",
    "default_cell",
    "load_cell",
]

logger = logging.getLogger(__name__)

MAX_NOISE_PULSES: Final = 10
"""Noise is encoder jitter; above this it would hide the 30-pulse in_motion threshold."""
MAX_BRAKE_SAG_PULSES: Final = 1000
"""Brake sag is small: users report a few thousandths of a radian (ros-industrial/motoman#501)."""


def default_cell(
    controller: str | ControllerType = DEFAULT_CONTROLLER, robot: str = DEFAULT_ROBOT
) -> CellConfig:
    """The embedded cell: an HC10 on a YRC1000 unless other models are named (the cell
    a file naming only ``[controller] model`` and ``[robot] model`` describes)."""
    ctrl = controller_model(controller)
    model = robot_model(robot)
    data = {
        "name": f"{model.name} on {ctrl.type.value}",
        "controller": {"model": ctrl.type.value},
        "robot": {"model": model.name},
    }
    return cell_from_dict(data, source="<default cell>")


def load_cell(path: str | Path) -> CellConfig:
    """Read a cell TOML file; a mistake raises ConfigError naming the key."""
    return cell_from_file(read_cell_file(path))


def cell_from_dict(
    data: Mapping[str, object], *, source: str = "<cell>", base_dir: Path | None = None
) -> CellConfig:
    """Build a cell from parsed TOML (see ``docs/cell.md``)."""
    return cell_from_file(cell_file_from_dict(data, source=source, base_dir=base_dir))


# ------------------------------------------------------------------------------ parsing


def cell_from_file(cell_file: CellFile) -> CellConfig:
    """The simulator's cell from a file :func:`~pymotoros.models.cell.read_cell_file`
    read: its controller and groups as every reader sees them, plus what only the
    simulator reads (servo, jobs, tools, the state at boot, peripherals)."""
    models = cell_file.models
    top = TomlTable(cell_file.data, "", cell_file.source)
    top.used.update(("name", "groups", "robot", "ports"))  # read by models/cell.py
    ctrl_t = top.table("controller")
    ctrl_t.used.update(("model", "fsu_speed_limit_pct"))  # read by models/cell.py
    ctrl = models.controller
    jobs = _jobs(ctrl_t, ctrl, cell_file.base_dir)
    servo = _servo(ctrl_t, models.fsu_speed_limit_pct)
    pfl = _pfl(ctrl_t, ctrl, models.robots)
    startup = _startup(ctrl_t)
    ctrl_t.finish()
    groups = models.robot.groups
    group_tools, s1cxg = _group_entries(top, cell_file.parts, len(groups))
    tools = _tools(top, "tools")
    numbers = {t.number for t in tools}.union(t.number for gt in group_tools for t in gt)
    initial = _initial(top.table("initial"), groups, numbers)
    peripherals = _peripherals(top, ctrl)
    fidelity = _fidelity(top.table("motoros"))
    top.used.add("workspace")  # obstacles: read by models/cell.py (models/workspace.py)
    workspace = models.workspace
    top.finish()
    for w in models.warnings:
        logger.warning("%s: %s", cell_file.source, w)
    return CellConfig(
        controller=ctrl,
        groups=groups,
        robots=models.robots,
        name=models.name,
        tools=tools,
        initial=initial,
        group_tools=group_tools if any(group_tools) else (),
        s1cxg=s1cxg if any(t is not None for t in s1cxg) else (),
        servo=servo,
        pfl=pfl,
        jobs=jobs,
        warnings=models.warnings,
        source=cell_file.source,
        startup=startup,
        peripherals=peripherals,
        model_groups=models.model_groups,
        workspace=workspace,
        fidelity=fidelity,
    )


def _fidelity(motoros_t: TomlTable) -> Fidelity:
    """``[motoros] fidelity = "exact" | "safe"`` (default exact, docs/fidelity.md)."""
    value = motoros_t.get("fidelity")
    fidelity = DEFAULT_FIDELITY
    if value is not None:
        try:
            fidelity = Fidelity.parse(value)
        except ValueError:
            raise motoros_t.error(
                "fidelity",
                f"must be 'exact' (as MotoROS 1.9.12 does it) or 'safe' (the twin's kinder "
                f"behaviour), not {value!r}",
            ) from None
    motoros_t.finish()
    return fidelity


def _jobs(
    ctrl_t: TomlTable, ctrl: ControllerModel, base_dir: Path | None
) -> str | tuple[Path, ...]:
    """``controller.jobs``: "auto", a built-in variant, or job files (checked now, with
    the key, rather than when the controller boots)."""
    value = ctrl_t.get("jobs")
    if value is None:
        return "auto"
    if isinstance(value, str) and value in ("auto", *BUILTIN_VARIANTS):
        return value
    if not isinstance(value, str | list):
        raise ctrl_t.error(
            "jobs", f"must be 'auto', one of {', '.join(BUILTIN_VARIANTS)} or job file paths"
        )
    items = [value] if isinstance(value, str) else value
    if not all(isinstance(i, str) for i in items):
        raise ctrl_t.error("jobs", "must be a variant name, a path or a list of paths")
    base = base_dir or Path.cwd()
    jobs = tuple(base / str(i) for i in items)
    for p in jobs:
        if not p.exists():
            raise ctrl_t.error("jobs", f"{p} does not exist")
    try:
        JobRunner(load_jobs(jobs), IoImage(ctrl))
    except JobError as exc:
        raise ctrl_t.error("jobs", str(exc)) from exc
    return jobs


def _servo(ctrl_t: TomlTable, fsu_speed_limit_pct: int | None) -> ServoConfig:
    return ServoConfig(
        servo_on_delay_ms=ctrl_t.integer("servo_on_delay_ms", SERVO_ON_DELAY_MS, 0, 4900),
        lag_ticks=ctrl_t.integer("feedback_lag_ticks", FEEDBACK_LAG_TICKS, 0, 50),
        noise_pulses=ctrl_t.integer("feedback_noise_pulses", 0, 0, MAX_NOISE_PULSES),
        brake_sag_pulses=ctrl_t.integer("brake_sag_pulses", 0, 0, MAX_BRAKE_SAG_PULSES),
        eco_idle_s=ctrl_t.optional_integer("eco_idle_s", 1, 86400),
        fsu_speed_limit_pct=fsu_speed_limit_pct,
    )


def _pfl(ctrl_t: TomlTable, ctrl: ControllerModel, robots: Sequence[str]) -> bool:
    """``controller.pfl``; by default on where the controller and a robot support it."""
    if ctrl_t.get("pfl") is None:
        return ctrl.pfl_signals and any(robot_model(r).pfl for r in robots)
    pfl = ctrl_t.boolean("pfl", False)
    if pfl and not ctrl.pfl_signals:
        raise ctrl_t.error(
            "pfl",
            f"the {ctrl.type.value} build of MotoROS has no PFL support "
            "(YRC1000 and YRC1000micro only)",
        )
    return pfl


def _group_entries(
    top: TomlTable, parts: Sequence[GroupPart], kept: int
) -> tuple[tuple[tuple[ToolConfig, ...], ...], tuple[S1cxgTable | None, ...]]:
    """Per group MotoROS keeps (the first ``kept``), the ``[[groups.tools]]`` and the
    ``[groups.s1cxg]`` of the ``[[groups]]`` entry that names it."""
    tools: list[tuple[ToolConfig, ...]] = [() for _ in parts]
    s1cxg: list[S1cxgTable | None] = [None for _ in parts]
    for i, entry in enumerate(top.array("groups")):
        g_t = TomlTable(entry, f"groups[{i}]", top.source)
        g_t.used.update(("robot", "group"))  # read by models/cell.py
        mine = [k for k, p in enumerate(parts) if p.entry == i]
        own = _tools(g_t, "tools")
        robots = [k for k in mine if parts[k].group.kind is GroupKind.ROBOT]
        if own and not robots:
            raise g_t.error("tools", "only robot groups take tools")
        for k in robots:
            tools[k] = own
        if g_t.get("s1cxg") is not None:
            if len(mine) != 1:
                raise g_t.error(
                    "s1cxg", 'applies to one group: add group = "R1" (or the group meant)'
                )
            s1cxg[mine[0]] = _s1cxg(g_t.table("s1cxg"), parts[mine[0]].group)
        g_t.finish()
    return tuple(tools[:kept]), tuple(s1cxg[:kept])


def _peripherals(top: TomlTable, ctrl: ControllerModel) -> tuple[PeripheralConfig, ...]:
    image = IoImage(ctrl)
    out: list[PeripheralConfig] = []
    for i, entry in enumerate(top.array("peripherals")):
        t = TomlTable(entry, f"peripherals[{i}]", top.source)
        addresses = [_peripheral_bit(t, key, image) for key in ("input", "follows")]
        if addresses[0] == addresses[1]:
            raise t.error("follows", "a peripheral cannot follow its own input")
        if addresses[0] in {p.input for p in out}:
            raise t.error("input", f"bit {addresses[0]} is already driven by another peripheral")
        out.append(
            PeripheralConfig(
                name=t.string("name", f"peripheral {i}"),
                input=addresses[0],
                follows=addresses[1],
                delay_ms=t.integer("delay_ms", 0, 0, MAX_DELAY_MS),
                invert=t.boolean("invert", False),
            )
        )
        t.finish()
    return tuple(out)


def _peripheral_bit(t: TomlTable, key: str, image: IoImage) -> int:
    address = t.optional_integer(key, 0, 10**6 - 1)
    if address is None:
        raise t.error(key, "is required (a bit address, e.g. 20010 or 10010)")
    try:
        image.check_forcible(address, 0)
    except ValueError as exc:
        raise t.error(key, str(exc)) from None
    return address


def _startup(ctrl_t: TomlTable) -> StartupConfig:
    software = ctrl_t.get("software")
    if software is not None and not isinstance(software, str):
        raise ctrl_t.error(
            "software", f"must be a string such as 'YAS2.80.00-00', not {software!r}"
        )
    params_t = ctrl_t.table("parameters")
    problems = check_parameters(params_t.data)
    if problems:
        raise params_t.error(problems[0].split(":", 1)[0], problems[0].split(":", 1)[1].strip())
    code = ctrl_t.get("validation_code")
    if code is not None and (
        not isinstance(code, int) or isinstance(code, bool) or not (code in (9, 10) or code > 11)
    ):
        raise ctrl_t.error(
            "validation_code", f"must be 9, 10 or an integer above 11 (e.g. 102), not {code!r}"
        )
    return StartupConfig(
        software=software,
        conveyor_tracking=ctrl_t.boolean("conveyor_tracking", False),
        parameters={k: int(v) for k, v in params_t.data.items() if isinstance(v, int)},
        validation_code=code,
    )


def _s1cxg(table: TomlTable, group: GroupModel) -> S1cxgTable:
    """A ``[groups.s1cxg]`` table (seed 003 Appendix A), for its entry's one group."""
    return parse_s1cxg(
        table.data,
        num_axes=group.num_axes,
        robot=group.kind is GroupKind.ROBOT,
        where=f"{table.source}: {table.path}",
    )


def _triple(t: TomlTable, name: str, unit: str) -> tuple[float, float, float]:
    values = t.array(name)
    nums = [float(x) for x in values if isinstance(x, int | float) and not isinstance(x, bool)]
    if values and (len(values) != 3 or len(nums) != 3 or not all(map(math.isfinite, nums))):
        raise t.error(name, f"must be three numbers in {unit}")
    return (nums[0], nums[1], nums[2]) if nums else (0.0, 0.0, 0.0)


def _tools(parent: TomlTable, key: str) -> tuple[ToolConfig, ...]:
    """The tool files of ``[[tools]]`` or ``[[groups.tools]]``: number 0..63, name, mass,
    TCP offset ``tcp_m = [x, y, z]`` and orientation ``rpy_rad = [r, p, y]`` on tool0."""
    tools = [
        _tool(TomlTable(entry, f"{parent.key(key)}[{i}]", parent.source))
        for i, entry in enumerate(parent.array(key))
    ]
    numbers = [t.number for t in tools]
    if len(set(numbers)) != len(numbers):
        dup = next(n for n in numbers if numbers.count(n) > 1)
        raise parent.error(key, f"tool {dup} appears twice")
    return tuple(tools)


def _tool(t_t: TomlTable) -> ToolConfig:
    number = t_t.optional_integer("number", 0, MAX_TOOL_NUMBER)
    if number is None:
        raise t_t.error("number", f"is required (0..{MAX_TOOL_NUMBER})")
    mass = t_t.number("mass_kg", 0.0)
    if mass < 0:
        raise t_t.error("mass_kg", f"must not be negative, not {mass}")
    tool = ToolConfig(
        number,
        t_t.string("name", ""),
        mass,
        _triple(t_t, "tcp_m", "metres [x, y, z]"),
        _triple(t_t, "rpy_rad", "radians [roll, pitch, yaw]"),
        _tool_shape(t_t),
    )
    t_t.finish()
    return tool


def _tool_shape(t_t: TomlTable) -> ToolShape | None:
    """A tool's ``shape`` (models/workspace.py reads it for the client too)."""
    value = t_t.get("shape")
    if value is None:
        return None
    try:
        return parse_tool_shape(value, t_t.key("shape"))
    except ConfigError as exc:
        raise ConfigError(f"{t_t.source}: {exc}") from None


def _initial(t: TomlTable, groups: tuple[GroupModel, ...], tool_numbers: set[int]) -> InitialState:
    mode_s = t.string("mode", "play")
    try:
        mode = PendantMode(mode_s.lower())
    except ValueError:
        raise t.error("mode", f"must be 'play' or 'teach', not {mode_s!r}") from None
    state = InitialState(
        mode=mode,
        remote=t.boolean("remote", True),
        servo=t.boolean("servo", False),
        estop=t.boolean("estop", False),
        hold=t.boolean("hold", False),
        eco=t.boolean("eco", False),
        alarms=_alarms(t),
        joints=_initial_joints(t.table("joints"), groups),
        tools=_initial_tools(t.table("tool"), groups, tool_numbers),
    )
    if state.servo and (state.estop or state.alarms):
        raise t.error("servo", "cannot be on at boot with an E-stop pressed or an alarm active")
    if state.eco and not state.servo:
        raise t.error("eco", "eco mode needs servo power on")
    t.finish()
    return state


def _refuse_unknown_groups(t: TomlTable, groups: Sequence[GroupModel]) -> None:
    names = [g.name for g in groups]
    unknown = sorted(set(t.data) - set(names))
    if unknown:
        raise t.error(unknown[0], f"no such group (groups: {', '.join(names)})")


def _initial_joints(
    joints_t: TomlTable, groups: Sequence[GroupModel]
) -> tuple[tuple[float, ...], ...]:
    """``[initial.joints]``: per group, ROS order, within the limits (absent: zeros)."""
    joints = [_group_joints(joints_t, g) for g in groups]
    _refuse_unknown_groups(joints_t, groups)
    return tuple(joints)


def _group_joints(joints_t: TomlTable, g: GroupModel) -> tuple[float, ...]:
    raw = joints_t.get(g.name)
    if raw is None:
        return tuple(0.0 for _ in g.axes)
    if not isinstance(raw, list) or not all(
        isinstance(x, int | float) and not isinstance(x, bool) for x in raw
    ):
        raise joints_t.error(g.name, "must be an array of numbers (rad, or m)")
    if len(raw) != g.num_axes:
        raise joints_t.error(g.name, f"needs {g.num_axes} values (ROS order), got {len(raw)}")
    for axis, value in zip(g.axes, raw, strict=True):
        if not axis.lower <= float(value) <= axis.upper:
            raise joints_t.error(
                g.name,
                f"{axis.name} = {value} is outside its limits {axis.lower:.4f}..{axis.upper:.4f}",
            )
    return tuple(float(x) for x in raw)


def _initial_tools(
    tools_t: TomlTable, groups: Sequence[GroupModel], tool_numbers: set[int]
) -> tuple[int, ...]:
    """``[initial.tool]``: per group, the selected tool (absent: 0)."""
    tools: list[int] = []
    for g in groups:
        n = tools_t.integer(g.name, 0, 0, MAX_TOOL_NUMBER)
        if n and g.kind is not GroupKind.ROBOT:
            raise tools_t.error(g.name, "only robot groups take tools")
        if n and tool_numbers and n not in tool_numbers:
            raise tools_t.error(g.name, f"tool {n} is not defined under [[tools]]")
        tools.append(n)
    _refuse_unknown_groups(tools_t, groups)
    return tuple(tools)


def _alarms(t: TomlTable) -> tuple[AlarmInfo, ...]:
    alarms: list[AlarmInfo] = []
    for i, entry in enumerate(t.array("alarms")):
        a_t = TomlTable(entry, f"{t.key('alarms')}[{i}]", t.source)
        code = a_t.optional_integer("code", 0, 9999)
        if code is None:
            raise a_t.error("code", "is required (0..9999)")
        subcode = a_t.integer("subcode", 0, 0, 2**31 - 1)
        alarms.append(AlarmInfo(code, subcode, a_t.string("text", "")))
        a_t.finish()
    return tuple(alarms)
