"""The client's picture of the tools: the tool files it knows and the one in force.

Every Cartesian operation (``tcp_pose``, ``move_pose``, ``move_linear``,
``move_relative``, ``pymotoros move --pose``, ``status``'s TCP line) places or reports
the TCP of the tool in force, so the client must know that tool. MotoROS reports
neither the tool data nor the selected tool, so the client never guesses:

* the tool data comes from the cell file (``RobotClient(cell=...)``, ``--config``) or
  from :meth:`ToolTable.define`;
* the tool in force is the one this client selected (:meth:`RobotClient.select_tool`),
  or the one the user names (``RobotClient(tool=N)``, :meth:`ToolTable.use`,
  ``--tool N``, ``PYMOTOROS_TOOL``). A selection made by another process (an earlier
  ``pymotoros tool N``) is not known to this one.

When no tool is named and the table defines tools for the group, the Cartesian
operation is refused (:class:`ToolUnknownError`); with no tool defined the TCP is
tool0 (tool 0 is selected after a controller boot, reference §5.8, and an unset tool
file has no offset).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Final

from pymotoros.client.planning import PlanningError
from pymotoros.models.cell_tools import CellTool
from pymotoros.models.robots import RobotModel, Transform
from pymotoros.protocol.constants import MAX_TOOL_NUMBER

if TYPE_CHECKING:  # the kinematics import numpy and Pinocchio: loaded when first used
    from pymotoros.kinematics import Chain

DEFAULT_TCP_SPEED_MM_S: Final = 250.0
"""Default TCP speed of a Cartesian move: the 250 mm/s of reduced-speed (T1) operation
in ISO 10218-1, a speed every robot programmer knows as "safe to watch"."""

_MM_PER_M: Final = 1000.0


class ToolUnknownError(PlanningError):
    """A Cartesian operation whose tool the client cannot know: name it (exit code 2)."""


class ToolTable:
    """Tool files per (group, number) and the tool in force of each group, when known."""

    def __init__(self, robot: RobotModel, tools: Sequence[Iterable[CellTool]] = ()) -> None:
        self._robot = robot
        self._tools: dict[tuple[int, int], CellTool] = {}
        self._chains: dict[tuple[int, int], Chain] = {}
        self.selected: dict[int, int] = {}
        """Per group, the tool in force as this client knows it (selected or named)."""
        for group, group_tools in enumerate(tools):
            for tool in group_tools:
                self._tools[(group, tool.number)] = tool

    def define(
        self,
        number: int,
        tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
        rpy_rad: Sequence[float] = (0.0, 0.0, 0.0),
        *,
        group: int = 0,
        name: str = "",
    ) -> None:
        """Tell the client tool file ``number``'s TCP offset on tool0 (m, rad)."""
        _check_number(number)
        if len(tcp_m) != 3 or len(rpy_rad) != 3:
            raise ValueError("a tool needs tcp_m = (x, y, z) and rpy_rad = (roll, pitch, yaw)")
        if not all(math.isfinite(float(v)) for v in (*tcp_m, *rpy_rad)):
            raise ValueError(f"tool {number}: tcp_m and rpy_rad must be finite numbers")
        frame = Transform(
            (float(tcp_m[0]), float(tcp_m[1]), float(tcp_m[2])),
            (float(rpy_rad[0]), float(rpy_rad[1]), float(rpy_rad[2])),
        )
        self._tools[(group, number)] = CellTool(number, name, frame)
        self._chains.pop((group, number), None)

    def use(self, number: int, *, group: int = 0) -> None:
        """Declare ``number`` the tool in force on ``group`` without sending SELECT_TOOL
        (it was selected on the pendant, by a job or by an earlier process)."""
        _check_number(number)
        self.selected[group] = number

    def defined(self, group: int = 0) -> tuple[CellTool, ...]:
        """The tool files known for ``group``, by number."""
        return tuple(sorted((t for (g, _), t in self._tools.items() if g == group), key=_num))

    def tool(self, group: int = 0, number: int | None = None) -> CellTool:
        """Tool file ``number`` (default: the one in force); a file never defined is empty
        (TCP = tool0), as an unset tool file on the controller."""
        n = self.in_force(group) if number is None else number
        _check_number(n)
        return self._tools.get((group, n), CellTool(n))

    def in_force(self, group: int = 0) -> int:
        """The tool in force on ``group``: the one selected or named; tool 0 when none is
        named and no tool is defined; else :class:`ToolUnknownError` (never a guess)."""
        if group in self.selected:
            return self.selected[group]
        known = self.defined(group)
        if not known:
            return 0
        listed = "; ".join(describe(t) for t in known)
        raise ToolUnknownError(
            f"which tool is in force on group {group} is unknown: the cell defines {listed}, "
            "and MotoROS cannot report the selected tool. Name it with --tool N (or "
            "PYMOTOROS_TOOL; in Python RobotClient(tool=N), tools.use(N) or select_tool(N))"
        )

    def describe(self, group: int = 0, number: int | None = None) -> str:
        """``tool 1 (gripper, TCP x 0.0 y 0.0 z 150.0 mm on tool0)``: the tool a line is
        about; without any tool data for the group, says so (a real robot's tool files are
        unknown until a cell file describes them)."""
        text = describe(self.tool(group, number))
        if not self.defined(group):
            text += "; no tool data known: describe the tools in the cell file (--config)"
        return text

    def chain(self, group: int = 0, tool: int | None = None) -> Chain:
        """The group's chain with ``tool`` (default: the one in force) on tool0. The chain
        and its workspace belong to this table (one per client, never shared)."""
        from pymotoros.kinematics import Chain

        data = self.tool(group, tool)
        key = (group, data.number)
        chain = self._chains.get(key)
        if chain is None:
            chain = self._chains[key] = Chain(self._robot.groups[group], data.tcp)
        return chain


def describe(tool: CellTool) -> str:
    """A tool as each Cartesian line names it: number, name and TCP offset."""
    x, y, z = (v * _MM_PER_M for v in tool.tcp.xyz)
    rx, ry, rz = (math.degrees(v) for v in tool.tcp.rpy)
    name = f"{tool.name}, " if tool.name else ""
    if not any((x, y, z, rx, ry, rz)):
        return f"tool {tool.number} ({name}TCP = tool0, no offset)"
    turn = f", Rx {rx:.1f} Ry {ry:.1f} Rz {rz:.1f} deg" if any((rx, ry, rz)) else ""
    return f"tool {tool.number} ({name}TCP x {x:.1f} y {y:.1f} z {z:.1f} mm{turn} on tool0)"


def _num(tool: CellTool) -> int:
    return tool.number


def _check_number(number: int) -> None:
    if not 0 <= number <= MAX_TOOL_NUMBER:
        raise ValueError(f"tool {number}: tool numbers are 0..{MAX_TOOL_NUMBER}")
