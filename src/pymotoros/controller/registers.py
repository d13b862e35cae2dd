"""The S1CxG register output functions, refreshed every interpolation period.

The rules (which value goes to which register, in which unit and size) are in
:mod:`pymotoros.models.s1cxg`; this module gathers the values from the servo model and
the kinematics each tick and writes the words into the M-registers of the IO image,
where the IO port, ``GET /api/io/{address}`` and the client read them. Nothing runs for
a cell without an S1CxG table, so the 4 ms tick pays nothing for the feature unless it
is used (docs/benchmarks.md gives the cost when it is).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from pymotoros.controller.cell import CellConfig
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.servo import ServoGroup
from pymotoros.controller.tcp import TcpTracker
from pymotoros.models.s1cxg import GroupValues, S1cxgTable, write_outputs

_MS_PER_S = 1000.0


class _GroupOutputs:
    """One group's table with what it needs to turn pulses into SI values."""

    def __init__(self, cell: CellConfig, index: int, table: S1cxgTable) -> None:
        group = cell.groups[index]
        self.index = index
        self.table = table
        n = group.num_axes
        slot_axis = {slot: ros for ros, slot in enumerate(group.moto_slots)}
        # Controller order: the k-th axis of the group is controller slot k (S, L, U, R,
        # B, T, then E on a 7-axis arm): the seed's "1st axis", "2nd axis" ...
        self.ppu = [group.axes[slot_axis[k]].pulses_per_unit for k in range(n)]
        self.linear = [group.axes[slot_axis[k]].linear for k in range(n)]
        self.ros_slots = tuple(group.moto_slots)
        self.num_axes = n
        self.kinematics = table.needs_kinematics
        # Re: the elbow angle of a 7-axis arm (its E axis, controller slot 6); 0 otherwise.
        self.e_slot = 6 if n == 7 else None


class RegisterOutputs:
    """Writes every group's S1CxG outputs into the M-registers each tick."""

    def __init__(
        self,
        cell: CellConfig,
        io: IoImage,
        tcp: TcpTracker,
        period_ms: int,
    ) -> None:
        self._groups = [
            _GroupOutputs(cell, g, table)
            for g, table in enumerate(cell.s1cxg)
            if table is not None and table.outputs
        ]
        self._io = io
        self._tcp = tcp
        self._per_s = _MS_PER_S / period_ms
        self._write: Callable[[int, int], None] = io.set_mregister

    @property
    def active(self) -> bool:
        return bool(self._groups)

    def refresh(
        self, servos: Sequence[ServoGroup], tools: Sequence[int], tick: int, powered: bool
    ) -> None:
        """Compute and write every output from the servos' state now."""
        for g in self._groups:
            servo = servos[g.index]
            n = g.num_axes
            cmd = servo.command[:n]
            fb = servo.feedback(tick, powered)[:n]
            inc = servo.last_increment
            fb_speed = servo.speed()
            ppu = g.ppu
            per_s = self._per_s
            pos_cmd = [cmd[k] / ppu[k] for k in range(n)]
            pos_fb = [fb[k] / ppu[k] for k in range(n)]
            spd_cmd = [inc[k] * per_s / ppu[k] for k in range(n)]
            spd_fb = [fb_speed[k] / ppu[k] for k in range(n)]
            cart_cmd: Sequence[float] = ()
            cart_fb: Sequence[float] = ()
            tcp_cmd = tcp_fb = 0.0
            if g.kinematics:
                chain = self._tcp.chain(g.index, tools[g.index])
                if chain is not None:
                    slots = g.ros_slots
                    q_cmd = [pos_cmd[s] for s in slots]
                    q_fb = [pos_fb[s] for s in slots]
                    re_cmd = pos_cmd[g.e_slot] if g.e_slot is not None else 0.0
                    re_fb = pos_fb[g.e_slot] if g.e_slot is not None else 0.0
                    cart_cmd = (*chain.pose(q_cmd), re_cmd)
                    cart_fb = (*chain.pose(q_fb), re_fb)
                    tcp_cmd = chain.tcp_velocity(q_cmd, [spd_cmd[s] for s in slots])
                    tcp_fb = chain.tcp_velocity(q_fb, [spd_fb[s] for s in slots])
            values = GroupValues(
                cartesian_command=cart_cmd,
                cartesian_feedback=cart_fb,
                pulse_command=cmd,
                pulse_feedback=fb,
                tcp_speed_command=tcp_cmd,
                tcp_speed_feedback=tcp_fb,
                axis_speed_command=spd_cmd,
                axis_speed_feedback=spd_fb,
                axis_position_command=pos_cmd,
                axis_position_feedback=pos_fb,
                linear=g.linear,
            )
            write_outputs(g.table, values, self._write)
