"""Which controller and which robots a cell file describes: the part the client needs too.

A cell TOML file (``docs/cell.md``) describes the simulator's whole cell: controller,
robots, tools, the state at boot. The client only needs the controller model (byte
order, IO map) and the control groups (names, axes, limits). Those rules live here, in
the models layer, so that :mod:`pymotoros.controller.cell` (the simulator) and the
client (``pymotoros move --config CELL.toml``) read a file the same way; the rest of the
file (tools, initial state, servo) stays the simulator's business and is ignored here.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Final

from pymotoros.errors import ConfigError
from pymotoros.models.controllers import DEFAULT_CONTROLLER, ControllerModel, controller_model
from pymotoros.models.robots import DEFAULT_ROBOT, GroupKind, GroupModel, RobotModel, robot_model
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
    workspace: Workspace = EMPTY_WORKSPACE
    """``[workspace]``: obstacles around the robot (models/workspace.py)."""


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


def _error(source: str, key: str, problem: str) -> ConfigError:
    return ConfigError(f"{source}: {key}: {problem}")


def _table(data: Mapping[str, object], key: str, source: str) -> Mapping[str, object]:
    value = data.get(key)
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ConfigError(f"{source}: {key} must be a table")
    return value


def _model_name(table: Mapping[str, object], key: str, name: str, default: str, kind: str) -> str:
    value = table.get(name, default)
    if not isinstance(value, str):
        raise ConfigError(f"{key}: must be a string, not {value!r}")
    try:
        if kind == "controller":
            controller_model(value)
        else:
            robot_model(value)
    except ConfigError as exc:
        raise ConfigError(f"{key}: {exc}") from None
    return value.lower()


def controller_name(data: Mapping[str, object], source: str) -> str:
    """``controller.model`` (default YRC1000), checked against the known controllers."""
    table = _table(data, "controller", source)
    try:
        return _model_name(
            table, "controller.model", "model", DEFAULT_CONTROLLER.value, "controller"
        )
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None


_GROUP_ENTRY_KEYS: Final = frozenset({"robot", "group", "tools", "s1cxg"})
"""Keys of a ``[[groups]]`` entry: the group, and the tool table and S1CxG register
parameters that the controller's cell loader reads from the same entry."""


def group_parts(data: Mapping[str, object], source: str) -> list[tuple[str, GroupModel]]:
    """The ``[robot]`` or ``[[groups]]`` of a cell file as (robot name, group) pairs.

    Every mistake names its key (``groups[1].robot``) and an unknown key is refused.
    """
    parts: list[tuple[str, GroupModel]] = []
    if "groups" in data and "robot" in data:
        raise _error(source, "groups", "give either [robot] or [[groups]], not both")
    if "groups" in data:
        entries = data["groups"]
        if not isinstance(entries, list):
            raise _error(source, "groups", f"must be an array, not {entries!r}")
        if not entries:
            raise _error(source, "groups", "needs at least one group")
        for i, entry in enumerate(entries):
            key = f"groups[{i}]"
            if not isinstance(entry, Mapping):
                raise ConfigError(f"{source}: {key} must be a table")
            try:
                robot_name = _model_name(entry, f"{key}.robot", "robot", DEFAULT_ROBOT, "robot")
            except ConfigError as exc:
                raise ConfigError(f"{source}: {exc}") from None
            model = robot_model(robot_name)
            wanted = entry.get("group")
            if wanted is None:
                parts.extend((model.name, g) for g in model.groups)
            else:
                match = [g for g in model.groups if g.name == wanted]
                if not match:
                    names = ", ".join(g.name for g in model.groups)
                    raise _error(
                        source, f"{key}.group", f"{model.name} has no group {wanted!r} ({names})"
                    )
                parts.append((model.name, match[0]))
            unknown = sorted(set(entry) - _GROUP_ENTRY_KEYS)
            if unknown:
                raise _error(source, f"{key}.{unknown[0]}", "unknown key (misspelt?)")
    else:
        table = _table(data, "robot", source)
        try:
            name = _model_name(table, "robot.model", "model", DEFAULT_ROBOT, "robot")
        except ConfigError as exc:
            raise ConfigError(f"{source}: {exc}") from None
        unknown = sorted(set(table) - {"model"})
        if unknown:
            raise _error(source, f"robot.{unknown[0]}", "unknown key (misspelt?)")
        model = robot_model(name)
        parts.extend((model.name, g) for g in model.groups)
    return parts


def cell_models_from_dict(data: Mapping[str, object], *, source: str = "<cell>") -> CellModels:
    """The controller and groups of a parsed cell file (other keys are not looked at)."""
    name = data.get("name", "cell")
    ctrl = controller_model(controller_name(data, source))
    warnings: list[str] = []
    groups, robots = combine_groups(ctrl, group_parts(data, source), warnings)
    first = robot_model(robots[0])
    robot = RobotModel(
        name=str(name),
        description=f"cell {name!s} ({', '.join(robots)})",
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
        workspace,
    )


FSU_PCT_RANGE: Final = (1, 100)
"""``controller.fsu_speed_limit_pct``: a share of each axis's maximum speed, in % (docs/cell.md)."""


def fsu_speed_limit_pct(data: Mapping[str, object], source: str) -> int | None:
    """``controller.fsu_speed_limit_pct`` of a parsed cell file (None when absent),
    checked as the simulator checks it: an integer within :data:`FSU_PCT_RANGE`."""
    value = _table(data, "controller", source).get("fsu_speed_limit_pct")
    if value is None:
        return None
    key = "controller.fsu_speed_limit_pct"
    if not isinstance(value, int) or isinstance(value, bool):
        raise _error(source, key, f"must be an integer, not {value!r}")
    lo, hi = FSU_PCT_RANGE
    if not lo <= value <= hi:
        raise _error(source, key, f"must lie in {lo}..{hi}, not {value}")
    return value


def load_cell_models(path: str | Path) -> CellModels:
    """Read the controller and groups of a cell TOML file (the simulator's format)."""
    p = Path(path)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read the cell file ({exc.strerror})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from exc
    return cell_models_from_dict(data, source=str(p))


__all__ = [
    "CellModels",
    "cell_models_from_dict",
    "combine_groups",
    "controller_name",
    "fsu_speed_limit_pct",
    "group_parts",
    "load_cell_models",
    "rename_groups",
]
