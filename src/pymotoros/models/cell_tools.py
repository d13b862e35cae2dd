"""The tool files of a cell file as the client needs them: number, name, TCP on tool0,
and the tool's collision shape (``shape``, docs/workspace.md).

MotoROS streams joint positions only and cannot report the tool data or which tool is
selected, so the client takes the tool data from the same cell file the simulator
reads (``[[tools]]`` for every robot group, ``[[groups.tools]]`` for one entry's
groups, the entry's own tool winning over a cell-wide one with the same number). The
simulator's reader (:mod:`pymotoros.controller.cell`) also checks mass and the boot
state; the rules here are the ones the TCP depends on, with the same key names in
every message.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

from pymotoros.errors import ConfigError
from pymotoros.models.robots import DEFAULT_ROBOT, GroupKind, GroupModel, Transform, robot_model
from pymotoros.models.workspace import ToolShape, parse_tool_shape
from pymotoros.protocol.constants import MAX_TOOL_NUMBER

NO_OFFSET: Final = Transform()
"""An unset tool file: the TCP is tool0 itself."""


@dataclass(frozen=True, slots=True)
class CellTool:
    """One tool file: its number (0..63), its name and its TCP frame on ``tool0``."""

    number: int
    name: str = ""
    tcp: Transform = NO_OFFSET
    shape: ToolShape | None = None
    """Its collision shape on the flange (``shape = {capsule = [r, length]}`` …); None:
    a capsule from the flange to the TCP (``workspace.tool_radius_m``)."""


def _triple(entry: Mapping[str, object], key: str, where: str, unit: str) -> tuple[float, ...]:
    value = entry.get(key, [0.0, 0.0, 0.0])
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        or not all(math.isfinite(float(v)) for v in value)
    ):
        raise ConfigError(f"{where}.{key}: must be three numbers in {unit}, not {value!r}")
    return tuple(float(v) for v in value)


def _tool_list(value: object, where: str) -> tuple[CellTool, ...]:
    """The tools of one ``[[tools]]`` / ``[[groups.tools]]`` array."""
    if value is None:
        return ()
    if not isinstance(value, list):
        raise ConfigError(f"{where}: must be an array of tables ([[...tools]])")
    tools: list[CellTool] = []
    for i, entry in enumerate(value):
        at = f"{where}[{i}]"
        if not isinstance(entry, Mapping):
            raise ConfigError(f"{at}: must be a table")
        number = entry.get("number")
        if not isinstance(number, int) or isinstance(number, bool):
            raise ConfigError(f"{at}.number: is required (0..{MAX_TOOL_NUMBER})")
        if not 0 <= number <= MAX_TOOL_NUMBER:
            raise ConfigError(f"{at}.number: must lie in 0..{MAX_TOOL_NUMBER}, not {number}")
        if any(t.number == number for t in tools):
            raise ConfigError(f"{where}: tool {number} appears twice")
        name = entry.get("name", "")
        xyz = _triple(entry, "tcp_m", at, "metres [x, y, z]")
        rpy = _triple(entry, "rpy_rad", at, "radians [roll, pitch, yaw]")
        frame = Transform((xyz[0], xyz[1], xyz[2]), (rpy[0], rpy[1], rpy[2]))
        shape_value = entry.get("shape")
        shape = None if shape_value is None else parse_tool_shape(shape_value, f"{at}.shape")
        tools.append(CellTool(number, str(name), frame, shape))
    return tuple(tools)


def cell_tools(
    data: Mapping[str, object], source: str, groups: Sequence[GroupModel]
) -> tuple[tuple[CellTool, ...], ...]:
    """Per group of ``groups`` (the cell's groups in controller order), its tool files.

    Groups that are not robots (bases, stations) take no tools: their tuple is empty.
    """
    try:
        shared = _tool_list(data.get("tools"), "tools")
        own: list[tuple[CellTool, ...]] = []
        entries = data.get("groups")
        for i, entry in enumerate(entries if isinstance(entries, list) else []):
            if not isinstance(entry, Mapping):
                continue  # group_parts has refused it already
            tools = _tool_list(entry.get("tools"), f"groups[{i}].tools")
            robot = str(entry.get("robot", DEFAULT_ROBOT))
            count = 1 if entry.get("group") is not None else len(robot_model(robot).groups)
            own.extend(tools for _ in range(count))
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    out: list[tuple[CellTool, ...]] = []
    for index, group in enumerate(groups):
        if group.kind is not GroupKind.ROBOT:
            out.append(())
            continue
        mine = own[index] if index < len(own) else ()
        numbers = {t.number for t in mine}
        out.append(mine + tuple(t for t in shared if t.number not in numbers))
    return tuple(out)


def initial_tools(data: Mapping[str, object], groups: Sequence[GroupModel]) -> tuple[int, ...]:
    """Per group, the tool ``[initial.tool]`` selects at boot (0 where it says nothing).
    The simulator's reader refuses a bad entry; here one is read as tool 0."""
    initial = data.get("initial")
    table = initial.get("tool") if isinstance(initial, Mapping) else None
    if not isinstance(table, Mapping):
        return ()
    out = []
    for group in groups:
        number = table.get(group.name, 0)
        valid = isinstance(number, int) and not isinstance(number, bool)
        out.append(number if valid and 0 <= number <= MAX_TOOL_NUMBER else 0)
    return tuple(out)


__all__ = ["CellTool", "cell_tools", "initial_tools"]
