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
from pymotoros.models.robots import GroupKind, Transform

MM_PER_M = 1000.0


class TcpTracker:
    """The kinematic chains of a cell's groups, with their tool files."""

    def __init__(self, cell: CellConfig) -> None:
        self._cell = cell
        self._period_s = cell.controller.interpolation_period_ms / 1000.0
        self._chains: list[Chain | None] = []
        self._with_tool: dict[tuple[int, int], Chain | None] = {}
        for group in cell.groups:
            try:
                self._chains.append(chain_for(group))
            except KinematicsError:
                self._chains.append(None)

    def chain(self, group_index: int, tool: int) -> Chain | None:
        """The group's chain with tool file ``tool`` on tool0 (None: no chain)."""
        key = (group_index, tool)
        if key not in self._with_tool:
            self._with_tool[key] = self._build(group_index, tool)
        return self._with_tool[key]

    def _build(self, group_index: int, tool: int) -> Chain | None:
        base = self._chains[group_index]
        if base is None:
            return None
        if self._cell.groups[group_index].kind is not GroupKind.ROBOT:
            return base
        t = self._cell.tool(group_index, tool)
        return chain_for(base.group, Transform(t.tcp_m, t.rpy_rad))

    def increment_speed_mm_s(
        self,
        group_index: int,
        tool: int,
        command_pulses: Sequence[int],
        increment: Sequence[int],
    ) -> float:
        """TCP speed (mm/s) of one tick that adds ``increment`` (controller-order pulses)
        to ``command_pulses``: the hook for an FSU TCP-speed limit, which can scale a
        tick's increments until this is within its limit. 0 for a group without a chain."""
        chain = self.chain(group_index, tool)
        if chain is None:
            return 0.0
        group = self._cell.groups[group_index]
        q = [
            command_pulses[s] / a.pulses_per_unit
            for a, s in zip(group.axes, group.moto_slots, strict=True)
        ]
        dq = [
            increment[s] / a.pulses_per_unit
            for a, s in zip(group.axes, group.moto_slots, strict=True)
        ]
        return chain.tcp_speed(q, dq, self._period_s) * MM_PER_M

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
        joint velocities (rad/s), ROS order. The speed is the distance the TCP travelled
        over the last period at these joint velocities (as the register outputs give it)."""
        chain = self.chain(group_index, tool)
        if chain is None:
            return None
        q_cmd = np.asarray(command, dtype=float)
        q_fb = np.asarray(feedback, dtype=float)
        d_cmd = np.asarray(command_velocity, dtype=float) * self._period_s
        d_fb = np.asarray(feedback_velocity, dtype=float) * self._period_s
        dt = self._period_s
        return TcpSnapshot(
            command=chain.pose(q_cmd),
            feedback=chain.pose(q_fb),
            command_speed_mm_s=chain.tcp_speed(q_cmd - d_cmd, d_cmd, dt) * MM_PER_M,
            feedback_speed_mm_s=chain.tcp_speed(q_fb - d_fb, d_fb, dt) * MM_PER_M,
        )

    def clip_increment(
        self,
        limit_mm_s: float,
        group_index: int,
        tool: int,
        command_pulses: Sequence[int],
        increment: Sequence[int],
    ) -> tuple[int, ...]:
        """The FSU's TCP-speed clip: the per-axis magnitudes of ``increment`` scaled so the
        TCP of ``tool`` moves at most ``limit_mm_s`` (rounded down per axis, so never above
        it); a group without a kinematic chain is not clipped."""
        speed = self.increment_speed_mm_s(group_index, tool, command_pulses, increment)
        scale = 1.0 if speed <= limit_mm_s else limit_mm_s / speed
        return tuple(int(abs(p) * scale) for p in increment)
