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
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

from pymotoros.controller.api import AlarmInfo, PendantMode
from pymotoros.controller.inform import BUILTIN_VARIANTS, JobRunner, load_jobs
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.peripherals import MAX_DELAY_MS, PeripheralConfig
from pymotoros.controller.safety.startup import StartupConfig, check_parameters
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
from pymotoros.models.cell import combine_groups, group_parts, rename_groups
from pymotoros.models.s1cxg import S1cxgTable, parse_s1cxg
from pymotoros.models.workspace import EMPTY_WORKSPACE, Workspace, workspace_from_dict
from pymotoros.protocol.constants import MAX_TOOL_NUMBER

logger = logging.getLogger(__name__)

SERVO_ON_DELAY_MS: Final = 500
"""Time from a servo-on request to 50073 (brakes released, amplifiers ready). Yaskawa
publishes no figure; about half a second is what an operator sees on the pendant
(modelling choice, docs/fidelity.md)."""
FEEDBACK_LAG_TICKS: Final = 3
"""Mean delay of the encoder feedback behind the command, in ticks (12 ms at 4 ms)."""
MAX_NOISE_PULSES: Final = 10
"""Noise is encoder jitter; above this it would hide the 30-pulse in_motion threshold."""
MAX_BRAKE_SAG_PULSES: Final = 1000
"""Brake sag is small: users report a few thousandths of a radian (ros-industrial/motoman#501)."""


@dataclass(frozen=True, slots=True)
class ToolConfig:
    """A tool file: number 0..63, with the data the PFL function relies on."""

    number: int
    name: str = ""
    mass_kg: float = 0.0
    tcp_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The TCP's orientation on tool0: fixed-axis roll, pitch, yaw (R = Rz·Ry·Rx)."""


@dataclass(frozen=True, slots=True)
class InitialState:
    """The controller at boot. Default: PLAY, REMOTE, servo off, nothing pressed or active."""

    mode: PendantMode = PendantMode.PLAY
    remote: bool = True
    servo: bool = False
    estop: bool = False
    hold: bool = False
    eco: bool = False
    alarms: tuple[AlarmInfo, ...] = ()
    joints: tuple[tuple[float, ...], ...] = ()
    """Per group, ROS order (rad, m); empty → every joint at 0."""
    tools: tuple[int, ...] = ()
    """Per group, the selected tool; empty → tool 0 (as after a reboot, §5.8)."""


@dataclass(frozen=True, slots=True)
class ServoConfig:
    servo_on_delay_ms: int = SERVO_ON_DELAY_MS
    lag_ticks: int = FEEDBACK_LAG_TICKS
    noise_pulses: int = 0
    brake_sag_pulses: int = 0
    """When servo power goes off (servo off, E-stop, eco mode) the brakes hold the axes
    a little away from where they were: each axis moves by a seeded amount within
    ±this many pulses, command and feedback alike (0: no sag)."""
    eco_idle_s: int | None = None
    """Eco mode starts after this many seconds with servo on and no motion (None: never)."""
    fsu_speed_limit_pct: int | None = None
    """A Functional Safety Unit joint-speed limit: the controller executes at most this
    share of each axis's maximum increment per tick and drops the rest (None: no FSU)."""


@dataclass(frozen=True, slots=True)
class CellConfig:
    """Everything :class:`~pymotoros.controller.VirtualController` needs to boot."""

    controller: ControllerModel
    groups: tuple[GroupModel, ...]
    robots: tuple[str, ...]
    """Robot model name of each group."""
    name: str = "cell"
    tools: tuple[ToolConfig, ...] = ()
    initial: InitialState = field(default_factory=InitialState)
    group_tools: tuple[tuple[ToolConfig, ...], ...] = ()
    """Per group, the tool files of ``[[groups.tools]]`` (empty: none beyond ``[[tools]]``)."""
    s1cxg: tuple[S1cxgTable | None, ...] = ()
    """Per group, the S1CxG register output parameters of ``[groups.s1cxg]`` (empty or
    None: no register outputs, the default)."""
    servo: ServoConfig = field(default_factory=ServoConfig)
    pfl: bool = False
    """The PFL option is enabled (HC robots on YRC1000 / YRC1000micro)."""
    jobs: str | tuple[Path, ...] = "auto"
    """A built-in INIT_ROS variant name, "auto", or job files/directories."""
    warnings: tuple[str, ...] = ()
    source: str = "<default cell>"
    startup: StartupConfig = field(default_factory=StartupConfig)
    peripherals: tuple[PeripheralConfig, ...] = ()
    """``[[peripherals]]``: inputs that follow other bits like devices (docs/cell.md)."""
    """What MotoROS's start-up checks read: software version, conveyor tracking, set-up
    parameters (``[controller]``, ``[controller.parameters]``)."""
    workspace: Workspace = EMPTY_WORKSPACE
    """``[workspace]``: obstacles the robot may touch (docs/workspace.md)."""

    def tool(self, group_index: int, number: int) -> ToolConfig:
        """Tool file ``number`` of a group: its own ``[[groups.tools]]`` entry, else the
        cell-wide ``[[tools]]`` one, else an empty tool (all zero, as an unset tool file)."""
        own = self.group_tools[group_index] if group_index < len(self.group_tools) else ()
        for t in (*own, *self.tools):
            if t.number == number:
                return t
        return ToolConfig(number)

    @property
    def job_variant(self) -> str | None:
        """The built-in job set to load (None when the cell names job files)."""
        if isinstance(self.jobs, tuple):
            return None
        if self.jobs != "auto":
            return self.jobs
        multi = len(self.groups) > 1
        if self.controller.skillsnd:
            return "dx100_multi_group" if multi else "dx100_single_arm"
        return "multi_group" if multi else "single_arm"


_rename = rename_groups
_combine = combine_groups


def default_cell(
    controller: str | ControllerType = DEFAULT_CONTROLLER, robot: str = DEFAULT_ROBOT
) -> CellConfig:
    """The embedded cell: an HC10 on a YRC1000 unless other models are named."""
    ctrl = controller_model(controller)
    model = robot_model(robot)
    warnings: list[str] = []
    groups, robots = _combine(ctrl, [(model.name, g) for g in model.groups], warnings)
    for w in warnings:
        logger.warning("%s", w)
    return CellConfig(
        controller=ctrl,
        groups=groups,
        robots=robots,
        name=f"{model.name} on {ctrl.type.value}",
        pfl=ctrl.pfl_signals and model.pfl,
        warnings=tuple(warnings),
    )


def load_cell(path: str | Path) -> CellConfig:
    """Read a cell TOML file; a mistake raises ConfigError naming the key."""
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read the cell file ({exc.strerror})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from exc
    return cell_from_dict(data, source=str(p), base_dir=p.parent)


# ------------------------------------------------------------------------------ parsing


class _Table:
    """A TOML table with its key path, so every error can name the key."""

    def __init__(self, data: object, path: str, source: str) -> None:
        if not isinstance(data, Mapping):
            raise ConfigError(f"{source}: {path or 'the file'} must be a table")
        self.data: Mapping[str, object] = data
        self.path = path
        self.source = source
        self.used: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def error(self, name: str, problem: str) -> ConfigError:
        return ConfigError(f"{self.source}: {self.key(name)}: {problem}")

    def get(self, name: str) -> object:
        self.used.add(name)
        return self.data.get(name)

    def string(self, name: str, default: str) -> str:
        v = self.get(name)
        if v is None:
            return default
        if not isinstance(v, str):
            raise self.error(name, f"must be a string, not {v!r}")
        return v

    def boolean(self, name: str, default: bool) -> bool:
        v = self.get(name)
        if v is None:
            return default
        if not isinstance(v, bool):
            raise self.error(name, f"must be true or false, not {v!r}")
        return v

    def integer(self, name: str, default: int, lo: int, hi: int) -> int:
        v = self.get(name)
        if v is None:
            return default
        if not isinstance(v, int) or isinstance(v, bool):
            raise self.error(name, f"must be an integer, not {v!r}")
        if not lo <= v <= hi:
            raise self.error(name, f"must lie in {lo}..{hi}, not {v}")
        return v

    def number(self, name: str, default: float) -> float:
        v = self.get(name)
        if v is None:
            return default
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise self.error(name, f"must be a finite number, not {v!r}")
        return float(v)

    def table(self, name: str) -> _Table:
        v = self.get(name)
        return _Table({} if v is None else v, self.key(name), self.source)

    def array(self, name: str) -> list[object]:
        v = self.get(name)
        if v is None:
            return []
        if not isinstance(v, list):
            raise self.error(name, f"must be an array, not {v!r}")
        return v

    def finish(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise self.error(unknown[0], "unknown key (misspelt?)")


def _model(table: _Table, name: str, default: str, kind: str) -> str:
    value = table.string(name, default)
    try:
        if kind == "controller":
            controller_model(value)
        else:
            robot_model(value)
    except ConfigError as exc:
        raise table.error(name, str(exc)) from None
    return value.lower()


def cell_from_dict(
    data: Mapping[str, object], *, source: str = "<cell>", base_dir: Path | None = None
) -> CellConfig:
    """Build a cell from parsed TOML (see ``docs/cell.md``)."""
    top = _Table(data, "", source)
    name = top.string("name", "cell")

    ctrl_t = top.table("controller")
    ctrl = controller_model(_model(ctrl_t, "model", DEFAULT_CONTROLLER.value, "controller"))
    jobs_value = ctrl_t.get("jobs")
    jobs: str | tuple[Path, ...] = "auto"
    if isinstance(jobs_value, str) and jobs_value in ("auto", *BUILTIN_VARIANTS):
        jobs = jobs_value
    elif isinstance(jobs_value, str | list):
        items = [jobs_value] if isinstance(jobs_value, str) else jobs_value
        if not all(isinstance(i, str) for i in items):
            raise ctrl_t.error("jobs", "must be a variant name, a path or a list of paths")
        base = base_dir or Path.cwd()
        jobs = tuple(base / str(i) for i in items)
        for p in jobs:
            if not p.exists():
                raise ctrl_t.error("jobs", f"{p} does not exist")
        try:  # refuse a bad job now, with the key, rather than when the controller boots
            JobRunner(load_jobs(jobs), IoImage(ctrl))
        except JobError as exc:
            raise ctrl_t.error("jobs", str(exc)) from exc
    elif jobs_value is not None:
        raise ctrl_t.error(
            "jobs", f"must be 'auto', one of {', '.join(BUILTIN_VARIANTS)} or job file paths"
        )
    servo = ServoConfig(
        servo_on_delay_ms=ctrl_t.integer("servo_on_delay_ms", SERVO_ON_DELAY_MS, 0, 4900),
        lag_ticks=ctrl_t.integer("feedback_lag_ticks", FEEDBACK_LAG_TICKS, 0, 50),
        noise_pulses=ctrl_t.integer("feedback_noise_pulses", 0, 0, MAX_NOISE_PULSES),
        brake_sag_pulses=ctrl_t.integer("brake_sag_pulses", 0, 0, MAX_BRAKE_SAG_PULSES),
        eco_idle_s=(
            ctrl_t.integer("eco_idle_s", 600, 1, 86400)
            if ctrl_t.data.get("eco_idle_s") is not None
            else None
        ),
        fsu_speed_limit_pct=(
            ctrl_t.integer("fsu_speed_limit_pct", 100, 1, 100)
            if ctrl_t.data.get("fsu_speed_limit_pct") is not None
            else None
        ),
    )
    pfl_value = ctrl_t.get("pfl")
    startup = _startup(ctrl_t)
    ctrl_t.finish()

    parts = group_parts(data, source)  # the rules the client shares (models/cell.py)
    top.used.update(("groups", "robot"))
    top.used.add("ports")  # where `pymotoros sim` listens: read by runtime/fleet.py
    entry_tools: list[tuple[ToolConfig, ...]] = []
    entry_s1cxg: list[S1cxgTable | None] = []
    """Per element of ``parts``, the ``[[groups.tools]]`` / ``[groups.s1cxg]`` of its entry."""
    if "groups" in data:
        at = 0
        for i, entry in enumerate(top.array("groups")):
            g_t = _Table(entry, f"groups[{i}]", source)
            count = 1 if g_t.get("group") is not None else len(robot_model(parts[at][0]).groups)
            mine = [g for _, g in parts[at : at + count]]
            at += count
            own = _tools(g_t, "tools", source)
            if own and not any(g.kind is GroupKind.ROBOT for g in mine):
                raise g_t.error("tools", "only robot groups take tools")
            entry_tools.extend(own if g.kind is GroupKind.ROBOT else () for g in mine)
            entry_s1cxg.extend(_s1cxg(g_t, mine))
            g_t.used.update(("robot", "group"))
            g_t.finish()
    else:
        entry_tools.extend(() for _ in parts)
        entry_s1cxg.extend(None for _ in parts)

    warnings: list[str] = []
    groups, robots = _combine(ctrl, parts, warnings)
    kept_entries = range(len(groups))  # _combine keeps the first max_groups parts, in order

    if pfl_value is None:
        pfl = ctrl.pfl_signals and any(robot_model(r).pfl for r in robots)
    elif isinstance(pfl_value, bool):
        pfl = pfl_value
        if pfl and not ctrl.pfl_signals:
            raise ConfigError(
                f"{source}: controller.pfl: the {ctrl.type.value} build of MotoROS has no PFL "
                "support (YRC1000 and YRC1000micro only)"
            )
    else:
        raise ConfigError(f"{source}: controller.pfl: must be true or false, not {pfl_value!r}")

    tools = _tools(top, "tools", source)
    numbers = {t.number for t in tools}
    group_tools = tuple(entry_tools[i] for i in kept_entries)
    s1cxg = tuple(entry_s1cxg[i] for i in kept_entries)
    for gt in group_tools:
        numbers.update(t.number for t in gt)

    initial = _initial(top.table("initial"), groups, numbers)
    peripherals = _peripherals(top, ctrl)
    top.used.add("workspace")  # obstacles: models/workspace.py
    workspace = workspace_from_dict(data.get("workspace"), source, [g.name for g in groups])
    top.finish()
    for w in warnings:
        logger.warning("%s: %s", source, w)
    return CellConfig(
        controller=ctrl,
        groups=groups,
        robots=robots,
        name=name,
        tools=tools,
        initial=initial,
        group_tools=group_tools if any(group_tools) else (),
        s1cxg=s1cxg if any(t is not None for t in s1cxg) else (),
        servo=servo,
        pfl=pfl,
        jobs=jobs,
        warnings=tuple(warnings),
        source=source,
        startup=startup,
        peripherals=peripherals,
        workspace=workspace,
    )


def _peripherals(top: _Table, ctrl: ControllerModel) -> tuple[PeripheralConfig, ...]:
    image = IoImage(ctrl)
    out: list[PeripheralConfig] = []
    for i, entry in enumerate(top.array("peripherals")):
        t = _Table(entry, f"peripherals[{i}]", top.source)
        addresses = []
        for key in ("input", "follows"):
            address = t.integer(key, -1, 0, 10**6 - 1)
            if address < 0:
                raise t.error(key, "is required (a bit address, e.g. 20010 or 10010)")
            try:
                image.check_forcible(address, 0)
            except ValueError as exc:
                raise t.error(key, str(exc)) from None
            addresses.append(address)
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


def _startup(ctrl_t: _Table) -> StartupConfig:
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


def _s1cxg(g_t: _Table, groups: Sequence[GroupModel]) -> list[S1cxgTable | None]:
    """The entry's ``[groups.s1cxg]`` table (seed 003 Appendix A), for its one group."""
    if g_t.get("s1cxg") is None:
        return [None] * len(groups)
    table = g_t.table("s1cxg")
    if len(groups) != 1:
        raise g_t.error("s1cxg", 'applies to one group: add group = "R1" (or the group meant)')
    group = groups[0]
    parsed = parse_s1cxg(
        table.data,
        num_axes=group.num_axes,
        robot=group.kind is GroupKind.ROBOT,
        where=f"{g_t.source}: {table.path}",
    )
    return [parsed]


def _triple(t: _Table, name: str, unit: str) -> tuple[float, float, float]:
    values = t.array(name)
    nums = [float(x) for x in values if isinstance(x, int | float) and not isinstance(x, bool)]
    if values and (len(values) != 3 or len(nums) != 3 or not all(map(math.isfinite, nums))):
        raise t.error(name, f"must be three numbers in {unit}")
    return (nums[0], nums[1], nums[2]) if nums else (0.0, 0.0, 0.0)


def _tools(parent: _Table, key: str, source: str) -> tuple[ToolConfig, ...]:
    """The tool files of ``[[tools]]`` or ``[[groups.tools]]``: number 0..63, name, mass,
    TCP offset ``tcp_m = [x, y, z]`` and orientation ``rpy_rad = [r, p, y]`` on tool0."""
    tools: list[ToolConfig] = []
    for i, entry in enumerate(parent.array(key)):
        t_t = _Table(entry, f"{parent.key(key)}[{i}]", source)
        number = t_t.integer("number", -1, 0, MAX_TOOL_NUMBER)
        if number < 0:
            raise t_t.error("number", f"is required (0..{MAX_TOOL_NUMBER})")
        mass = t_t.number("mass_kg", 0.0)
        if mass < 0:
            raise t_t.error("mass_kg", f"must not be negative, not {mass}")
        tools.append(
            ToolConfig(
                number,
                t_t.string("name", ""),
                mass,
                _triple(t_t, "tcp_m", "metres [x, y, z]"),
                _triple(t_t, "rpy_rad", "radians [roll, pitch, yaw]"),
            )
        )
        t_t.finish()
    numbers = [t.number for t in tools]
    if len(set(numbers)) != len(numbers):
        dup = next(n for n in numbers if numbers.count(n) > 1)
        raise parent.error(key, f"tool {dup} appears twice")
    return tuple(tools)


def _initial(t: _Table, groups: tuple[GroupModel, ...], tool_numbers: set[int]) -> InitialState:
    mode_s = t.string("mode", "play")
    try:
        mode = PendantMode(mode_s.lower())
    except ValueError:
        raise t.error("mode", f"must be 'play' or 'teach', not {mode_s!r}") from None
    names = [g.name for g in groups]

    joints_t = t.table("joints")
    joints: list[tuple[float, ...]] = []
    for g in groups:
        raw = joints_t.get(g.name)
        if raw is None:
            joints.append(tuple(0.0 for _ in g.axes))
            continue
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
                    f"{axis.name} = {value} is outside its limits "
                    f"{axis.lower:.4f}..{axis.upper:.4f}",
                )
        joints.append(tuple(float(x) for x in raw))
    unknown = sorted(set(joints_t.data) - set(names))
    if unknown:
        raise joints_t.error(unknown[0], f"no such group (groups: {', '.join(names)})")

    tools_t = t.table("tool")
    tools: list[int] = []
    for g in groups:
        n = tools_t.integer(g.name, 0, 0, MAX_TOOL_NUMBER)
        if n and g.kind is not GroupKind.ROBOT:
            raise tools_t.error(g.name, "only robot groups take tools")
        if n and tool_numbers and n not in tool_numbers:
            raise tools_t.error(g.name, f"tool {n} is not defined under [[tools]]")
        tools.append(n)
    unknown = sorted(set(tools_t.data) - set(names))
    if unknown:
        raise tools_t.error(unknown[0], f"no such group (groups: {', '.join(names)})")

    alarms: list[AlarmInfo] = []
    for i, entry in enumerate(t.array("alarms")):
        a_t = _Table(entry, f"{t.key('alarms')}[{i}]", t.source)
        code = a_t.integer("code", -1, 0, 9999)
        if code < 0:
            raise a_t.error("code", "is required (0..9999)")
        subcode = a_t.integer("subcode", 0, 0, 2**31 - 1)
        alarms.append(AlarmInfo(code, subcode, a_t.string("text", "")))
        a_t.finish()

    state = InitialState(
        mode=mode,
        remote=t.boolean("remote", True),
        servo=t.boolean("servo", False),
        estop=t.boolean("estop", False),
        hold=t.boolean("hold", False),
        eco=t.boolean("eco", False),
        alarms=tuple(alarms),
        joints=tuple(joints),
        tools=tuple(tools),
    )
    if state.servo and (state.estop or state.alarms):
        raise t.error("servo", "cannot be on at boot with an E-stop pressed or an alarm active")
    if state.eco and not state.servo:
        raise t.error("eco", "eco mode needs servo power on")
    t.finish()
    return state
