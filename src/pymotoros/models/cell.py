"""The cell file, read once: which controller and robots it describes, and where it listens.

A cell TOML file (``docs/cell.md``) describes the simulator's whole cell: controller,
robots, tools, the state at boot, its ports. :func:`read_cell_file` is the one place that
opens such a file; everyone reads it through there and looks at the part it needs:

* the client (``RobotClient(cell=...)``, ``pymotoros move --config CELL.toml``) and the
  offline ``check`` / ``plan`` need the controller model (byte order, IO map) and the
  control groups (names, axes, limits) and the tools' TCPs
  (:mod:`pymotoros.models.cell_tools`): :attr:`CellFile.models`;
* ``pymotoros sim`` and its fleet need the ``[ports]`` table: :attr:`CellFile.ports`;
* the simulator (:func:`pymotoros.controller.cell.cell_from_file`) reads the rest (tools,
  initial state, servo, jobs) from :attr:`CellFile.data`, on top of the same groups.

So a file means the same to each of them, and a mistake in the shared part is refused
with the same words whoever reads it. These rules live in the models layer, which the
client, the controller and the runtime may all import.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Final, NamedTuple

from pymotoros.errors import ConfigError
from pymotoros.models.cell_tools import CellTool, cell_tools, initial_tools
from pymotoros.models.controllers import DEFAULT_CONTROLLER, ControllerModel, controller_model
from pymotoros.models.robots import DEFAULT_ROBOT, GroupKind, GroupModel, RobotModel, robot_model
from pymotoros.models.toml_file import TomlTable, read_toml
from pymotoros.models.workspace import EMPTY_WORKSPACE, Workspace, workspace_from_dict


@dataclass(frozen=True, slots=True)
class CellModels:
    """The controller and the control groups of a cell, as the client sees them."""

    name: str
    controller: ControllerModel
    robot: RobotModel
    """One model whose groups are the cell's groups in controller order (R1, R2, B1 …)."""
    robots: tuple[str, ...]
    """Robot model name of each group."""
    warnings: tuple[str, ...] = ()
    fsu_speed_limit_pct: int | None = None
    """``controller.fsu_speed_limit_pct``: the FSU joint-speed limit at boot (each axis
    executes at most this share of its maximum increment per tick); None: no FSU.
    The offline check (``pymotoros check --config``) predicts its effect."""
    model_groups: tuple[str, ...] = ()
    """Each group's name in its robot model (the second HC10 of a cell is the
    controller's R2 but its model's R1): with :attr:`robots`, what a ``[[groups]]``
    entry names, so that :func:`cell_table` can write the cell back."""
    tools: tuple[tuple[CellTool, ...], ...] = ()
    """Per group, its tool files (``[[tools]]``, ``[[groups.tools]]``): the TCPs the
    client's Cartesian operations use (:mod:`pymotoros.models.cell_tools`)."""

    workspace: Workspace = EMPTY_WORKSPACE
    """``[workspace]``: obstacles around the robot (models/workspace.py)."""
    initial_tools: tuple[int, ...] = ()
    """Per group, the tool selected at boot (``[initial.tool]``; empty: tool 0)."""

    def default_tool(self, group_index: int) -> int:
        """The tool a group has when nobody selected one: the cell's ``[initial.tool]``,
        else tool 0 (as after a controller boot, reference §5.8). The twin boots with it,
        and ``check`` / ``plan --avoid`` put its shape on the flange."""
        tools = self.initial_tools
        return tools[group_index] if group_index < len(tools) else 0


PORT_KINDS: Final = ("motion", "state", "io", "http")
"""The servers of one cell, in the order of ``pymotoros sim``'s ready line."""

MAX_PORT: Final = 65535
"""The largest TCP port number."""


@dataclass(frozen=True, slots=True)
class CellPorts:
    """The ``[ports]`` table of a cell file; None where the file does not set a port."""

    motion: int | None = None
    state: int | None = None
    io: int | None = None
    http: int | None = None

    def get(self, kind: str) -> int | None:
        value: int | None = getattr(self, kind)
        return value


class GroupPart(NamedTuple):
    """One control group a cell file names, before the controller's cap and renaming."""

    robot: str
    """The robot model's name."""
    group: GroupModel
    """The group as the robot model names it."""
    entry: int
    """Index of the ``[[groups]]`` entry that names it (0 for a ``[robot]`` table)."""


@dataclass(frozen=True, slots=True)
class CellFile:
    """A cell file read once, with the parts every reader shares already checked."""

    data: Mapping[str, object]
    """The whole parsed file (the simulator reads its own tables from it)."""
    source: str
    """Where it came from, the first word of every error (the path)."""
    base_dir: Path | None
    """The folder relative job paths start from (None: the working directory)."""
    models: CellModels
    ports: CellPorts
    parts: tuple[GroupPart, ...]
    """Every group the file names, in order, before the controller's group cap."""


def rename_groups(groups: Sequence[GroupModel]) -> tuple[GroupModel, ...]:
    """Number groups per kind in order (R1, R2, B1 …) as the controller does."""
    counters: dict[GroupKind, int] = {}
    out = []
    for g in groups:
        counters[g.kind] = counters.get(g.kind, 0) + 1
        out.append(replace(g, name=f"{g.kind.value}{counters[g.kind]}"))
    return tuple(out)


def combine_groups(
    controller: ControllerModel,
    parts: Sequence[tuple[str, GroupModel]],
    warnings: list[str],
) -> tuple[tuple[GroupModel, ...], tuple[str, ...]]:
    """The groups MotoROS uses (at most ``max_groups``, renamed); unusual combinations warned."""
    seen: set[str] = set()
    for robot_name, _ in parts:
        robot = robot_model(robot_name)
        if robot_name not in seen and controller.type.value not in robot.controllers:
            sold = ", ".join(sorted(robot.controllers)) or "no controller"
            warnings.append(
                f"robot {robot.name} is not sold with a {controller.type.value} controller "
                f"(it runs on {sold}); simulating the combination anyway"
            )
        seen.add(robot_name)
    if len(parts) > controller.max_groups:
        warnings.append(
            f"{len(parts)} control groups, but MotoROS uses at most {controller.max_groups} "
            f"on {controller.type.value}; groups after the {controller.max_groups}th are ignored"
        )
        parts = parts[: controller.max_groups]
    groups = rename_groups([g for _, g in parts])
    return groups, tuple(r for r, _ in parts)


def _model_name(table: TomlTable, name: str, default: str, kind: str) -> str:
    """A controller or robot model name at ``name``, checked against the known models."""
    value = table.string(name, default)
    try:
        if kind == "controller":
            controller_model(value)
        else:
            robot_model(value)
    except ConfigError as exc:
        raise table.error(name, str(exc)) from None
    return value.lower()


def controller_name(data: Mapping[str, object], source: str) -> str:
    """``controller.model`` (default YRC1000), checked against the known controllers."""
    table = TomlTable(data, "", source).table("controller")
    return _model_name(table, "model", DEFAULT_CONTROLLER.value, "controller")


_GROUP_ENTRY_KEYS: Final = frozenset({"robot", "group", "tools", "s1cxg"})
"""Keys of a ``[[groups]]`` entry: the group, and the tool table and S1CxG register
parameters that the controller's cell loader reads from the same entry."""


def _entry_parts(entry: object, index: int, source: str) -> list[GroupPart]:
    """The groups one ``[[groups]]`` entry names: all of its robot's, or its ``group``."""
    table = TomlTable(entry, f"groups[{index}]", source)
    model = robot_model(_model_name(table, "robot", DEFAULT_ROBOT, "robot"))
    wanted = table.get("group")
    unknown = sorted(set(table.data) - _GROUP_ENTRY_KEYS)
    if wanted is None:
        chosen = list(model.groups)
    else:
        chosen = [g for g in model.groups if g.name == wanted]
        if not chosen:
            names = ", ".join(g.name for g in model.groups)
            raise table.error("group", f"{model.name} has no group {wanted!r} ({names})")
    if unknown:
        raise table.error(unknown[0], "unknown key (misspelt?)")
    return [GroupPart(model.name, g, index) for g in chosen]


def cell_parts(data: Mapping[str, object], source: str) -> tuple[GroupPart, ...]:
    """The ``[robot]`` or ``[[groups]]`` of a cell file as its groups, in order.

    Every mistake names its key (``groups[1].robot``) and an unknown key is refused.
    """
    top = TomlTable(data, "", source)
    if "groups" in data and "robot" in data:
        raise top.error("groups", "give either [robot] or [[groups]], not both")
    if "groups" in data:
        entries = top.array("groups")
        if not entries:
            raise top.error("groups", "needs at least one group")
        return tuple(p for i, e in enumerate(entries) for p in _entry_parts(e, i, source))
    table = top.table("robot")
    model = robot_model(_model_name(table, "model", DEFAULT_ROBOT, "robot"))
    table.finish()
    return tuple(GroupPart(model.name, g, 0) for g in model.groups)


def group_parts(data: Mapping[str, object], source: str) -> list[tuple[str, GroupModel]]:
    """:func:`cell_parts` as (robot name, group) pairs."""
    return [(p.robot, p.group) for p in cell_parts(data, source)]


def _models(data: Mapping[str, object], source: str, parts: Sequence[GroupPart]) -> CellModels:
    name = TomlTable(data, "", source).string("name", "cell")
    ctrl = controller_model(controller_name(data, source))
    warnings: list[str] = []
    groups, robots = combine_groups(ctrl, [(p.robot, p.group) for p in parts], warnings)
    first = robot_model(robots[0])
    robot = RobotModel(
        name=name,
        description=f"cell {name} ({', '.join(robots)})",
        groups=groups,
        controllers=first.controllers,
        pfl=any(robot_model(r).pfl for r in robots),
    )
    workspace = workspace_from_dict(data.get("workspace"), source, [g.name for g in groups])
    return CellModels(
        str(name),
        ctrl,
        robot,
        robots,
        tuple(warnings),
        fsu_speed_limit_pct(data, source),
        tuple(p.group.name for p in parts[: len(groups)]),
        cell_tools(data, source, groups),
        workspace,
        initial_tools(data, groups),
    )


def cell_models_from_dict(data: Mapping[str, object], *, source: str = "<cell>") -> CellModels:
    """The controller and groups of a parsed cell file (other keys are not looked at)."""
    return _models(data, source, cell_parts(data, source))


FSU_PCT_RANGE: Final = (1, 100)
"""``controller.fsu_speed_limit_pct``: a share of each axis's maximum speed, in % (docs/cell.md)."""


def fsu_speed_limit_pct(data: Mapping[str, object], source: str) -> int | None:
    """``controller.fsu_speed_limit_pct`` of a parsed cell file (None when absent),
    checked as the simulator checks it: an integer within :data:`FSU_PCT_RANGE`."""
    table = TomlTable(data, "", source).table("controller")
    return table.optional_integer("fsu_speed_limit_pct", *FSU_PCT_RANGE)


def cell_ports(data: Mapping[str, object], source: str) -> CellPorts:
    """The ``[ports]`` table of a parsed cell file (every port None when it has none)."""
    if not isinstance(data.get("ports", {}), Mapping):
        raise ConfigError(f"{source}: ports must be a table ([ports] motion = ..., http = ...)")
    table = TomlTable(data, "", source).table("ports")
    unknown = sorted(set(table.data) - set(PORT_KINDS))
    if unknown:
        raise table.error(
            unknown[0], f"unknown key (misspelt?); the keys are {', '.join(PORT_KINDS)}"
        )
    return CellPorts(
        **{
            kind: table.optional_integer(kind, 0, MAX_PORT)
            for kind in PORT_KINDS
            if kind in table.data
        }
    )


def cell_file_from_dict(
    data: Mapping[str, object], *, source: str = "<cell>", base_dir: Path | None = None
) -> CellFile:
    """A parsed cell file with its shared parts checked (models, groups, ports)."""
    TomlTable(data, "", source)  # the whole file must be a table
    parts = cell_parts(data, source)
    return CellFile(
        data, source, base_dir, _models(data, source, parts), cell_ports(data, source), parts
    )


def read_cell_file(path: str | Path) -> CellFile:
    """Read a cell TOML file: the one reader of the format (``docs/cell.md``)."""
    p = Path(path)
    return cell_file_from_dict(read_toml(p, "cell file"), source=str(p), base_dir=p.parent)


def load_cell_models(path: str | Path) -> CellModels:
    """Read the controller and groups of a cell TOML file (the simulator's format)."""
    return read_cell_file(path).models


def cell_table(
    name: str, controller: str, robots: Sequence[str], model_groups: Sequence[str]
) -> dict[str, Any]:
    """A cell's name, controller and groups in the cell file's own shape (JSON-able):
    :func:`cell_models_from_dict` reads it back into the same models. ``robots`` and
    ``model_groups`` name each group by its robot model and its name in that model."""
    return {
        "name": name,
        "controller": {"model": controller},
        "groups": [
            {"robot": robot, "group": group}
            for robot, group in zip(robots, model_groups, strict=True)
        ],
    }


__all__ = [
    "PORT_KINDS",
    "CellFile",
    "CellModels",
    "CellPorts",
    "GroupPart",
    "cell_file_from_dict",
    "cell_models_from_dict",
    "cell_parts",
    "cell_ports",
    "cell_table",
    "combine_groups",
    "controller_name",
    "fsu_speed_limit_pct",
    "group_parts",
    "load_cell_models",
    "read_cell_file",
    "rename_groups",
]
