"""Where each group's tool is: the active tool's TCP pose and speed for the snapshot.

Computed only when a snapshot is taken (HTTP ``GET /api/state``, observers), never in
the 4 ms tick: the kinematics cost tens of microseconds per group.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pymotoros.controller.api import TcpSnapshot
from pymotoros.controller.cell import CellConfig
from pymotoros.errors import KinematicsError
from pymotoros.kinematics import Chain, chain_for
from pymotoros.models.robots import Frame, GroupKind

MM_PER_M = 1000.0


class TcpTracker:
    """The kinematic chains of a cell's groups, with their tool files."""

    def __init__(self, cell: CellConfig) -> None:
        self._cell = cell
        self._chains: list[Chain | None] = []
        for group in cell.groups:
            try:
                self._chains.append(chain_for(group))
            except KinematicsError:
                self._chains.append(None)

    def chain(self, group_index: int, tool: int) -> Chain | None:
        """The group's chain with tool file ``tool`` on tool0 (None: no chain)."""
        base = self._chains[group_index]
        if base is None:
            return None
        if self._cell.groups[group_index].kind is not GroupKind.ROBOT:
            return base
        t = self._cell.tool(group_index, tool)
        return chain_for(base.group, Frame(t.tcp_m, t.rpy_rad))

    def snapshot(
        self,
        group_index: int,
        tool: int,
        command: Sequence[float],
        feedback: Sequence[float],
        command_velocity: Sequence[float],
        feedback_velocity: Sequence[float],
    ) -> TcpSnapshot | None:
        """TCP pose in base coordinates and TCP speed (mm/s) from joint values (rad) and
        joint velocities (rad/s), ROS order."""
        chain = self.chain(group_index, tool)
        if chain is None:
            return None
        return TcpSnapshot(
            command=chain.pose(np.asarray(command, dtype=float)),
            feedback=chain.pose(np.asarray(feedback, dtype=float)),
            command_speed_mm_s=chain.tcp_velocity(command, command_velocity) * MM_PER_M,
            feedback_speed_mm_s=chain.tcp_velocity(feedback, feedback_velocity) * MM_PER_M,
        )
