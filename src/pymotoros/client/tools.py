"""The client's picture of the tools: tool files it was told about and the one selected.

A real controller does not report its tool data over MotoROS, so the client holds the
same tool table the cell file gives the twin (:meth:`ToolTable.define`); SELECT_TOOL
through the client switches the TCP it computes from the joint feedback. Tool 0 is
selected after connecting, as after a controller boot (reference §5.8).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Final

from pymotoros.models.robots import RobotModel, Transform
from pymotoros.protocol.constants import MAX_TOOL_NUMBER

if TYPE_CHECKING:  # the kinematics import numpy and Pinocchio: loaded when first used
    from pymotoros.kinematics import Chain

DEFAULT_TCP_SPEED_MM_S: Final = 250.0
"""Default TCP speed of a Cartesian move: the 250 mm/s of reduced-speed (T1) operation
in ISO 10218-1, a speed every robot programmer knows as "safe to watch"."""


class ToolTable:
    """Tool offsets per (group, number) and the selected tool of each group."""

    def __init__(self, robot: RobotModel) -> None:
        self._robot = robot
        self._frames: dict[tuple[int, int], Transform] = {}
        self.selected: dict[int, int] = {}

    def define(
        self,
        number: int,
        tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
        rpy_rad: Sequence[float] = (0.0, 0.0, 0.0),
        *,
        group: int = 0,
    ) -> None:
        """Tell the client tool file ``number``'s TCP offset on tool0 (m, rad)."""
        if not 0 <= number <= MAX_TOOL_NUMBER:
            raise ValueError(f"tool {number}: tool numbers are 0..{MAX_TOOL_NUMBER}")
        if len(tcp_m) != 3 or len(rpy_rad) != 3:
            raise ValueError("a tool needs tcp_m = (x, y, z) and rpy_rad = (roll, pitch, yaw)")
        self._frames[(group, number)] = Transform(
            (float(tcp_m[0]), float(tcp_m[1]), float(tcp_m[2])),
            (float(rpy_rad[0]), float(rpy_rad[1]), float(rpy_rad[2])),
        )

    def chain(self, group: int = 0, tool: int | None = None) -> Chain:
        """The group's chain with ``tool`` (default: the selected one) on tool0; a tool
        never defined is empty (TCP = tool0), as an unset tool file on the controller."""
        from pymotoros.kinematics import chain_for

        number = self.selected.get(group, 0) if tool is None else tool
        frame = self._frames.get((group, number), Transform())
        return chain_for(self._robot.groups[group], frame)
