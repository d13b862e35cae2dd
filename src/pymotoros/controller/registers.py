"""The S1CxG register output functions: the M-registers as they are after each tick.

The rules (which value goes to which register, in which unit and size) are in
:mod:`pymotoros.models.s1cxg`. This module compiles a group's table once into index and
scale arrays; to write the words it gathers the values from the servo model and the
kinematics into one vector and computes every register word with a few numpy operations
(the tests compare them with the rule applied output by output,
``tests/oracles/s1cxg.py``). That costs tens of microseconds while the arm moves (two
forward kinematics and more per group), which is why it is not done in the tick.

A real controller writes the words every interpolation period. Here the tick only keeps
what that would read at its place in the tick (each table's servo state, a few short
tuples from :meth:`~pymotoros.controller.servo.ServoGroup.state`, the tool, the tick
count, drive power): every M-register access goes through the IO image, which calls
:meth:`RegisterOutputs.materialise` first, and that computes the latest tick's words
from what it kept. Only the latest tick's words can be seen, since each tick rewrites
them all, so a reader sees bit for bit what a controller writing every tick would show,
even when the servos moved after the tick's step (an E-stop's brake sag, a scenario); a
client's write between ticks lands on those words and stays until the next tick. Several
reads between two ticks compute once. The route that computes the words in every tick,
as the controller does, is the tests' oracle (``tests/oracles/registers.py``), compared
reader by reader. Nothing runs for a cell without an S1CxG table.

TCP speed, here and in the snapshot, is the distance the TCP travels over one step of the
joints divided by its time (:meth:`~pymotoros.kinematics.Chain.tcp_speed`): the command's
last 4 ms increment, and the feedback's averaged speed over one period.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Sequence
from typing import Final, Protocol

import numpy as np
import numpy.typing as npt

from pymotoros.controller.cell import CellConfig
from pymotoros.controller.servo import ServoGroup, ServoState
from pymotoros.controller.tool_point import TcpTracker
from pymotoros.kinematics import matrix_to_pose
from pymotoros.models.s1cxg import Quantity, S1cxgTable, Source, unit_scale

_MS_PER_S: Final = 1000.0
_CART: Final = 7  # X, Y, Z, Rx, Ry, Rz, Re


class _Plan:
    """One group's table compiled into arrays over a value vector laid out as
    [cartesian cmd (7), cartesian fb (7), position cmd (n), position fb (n), speed cmd (n),
    speed fb (n), TCP speed cmd, TCP speed fb, pulses cmd (n), pulses fb (n)]."""

    def __init__(self, cell: CellConfig, index: int, table: S1cxgTable) -> None:
        group = cell.groups[index]
        n = group.num_axes
        self.index = index
        self.num_axes = n
        slot_axis = {slot: ros for ros, slot in enumerate(group.moto_slots)}
        # The k-th axis of the seed ("1st axis" ...) is controller slot k: S, L, U, R, B,
        # T, then E on a 7-axis arm.
        axes = [group.axes[slot_axis[k]] for k in range(n)]
        self.ppu_list = [a.pulses_per_unit for a in axes]
        self.ros_slot_list = list(group.moto_slots)
        self.identity = self.ros_slot_list == list(range(n))
        self.e_slot = 6 if n == 7 else None  # Re: a 7-axis arm's elbow (E) angle
        base = {
            (Quantity.CARTESIAN, Source.COMMAND): 0,
            (Quantity.CARTESIAN, Source.FEEDBACK): _CART,
            (Quantity.AXIS_POSITION, Source.COMMAND): 2 * _CART,
            (Quantity.AXIS_POSITION, Source.FEEDBACK): 2 * _CART + n,
            (Quantity.AXIS_SPEED, Source.COMMAND): 2 * _CART + 2 * n,
            (Quantity.AXIS_SPEED, Source.FEEDBACK): 2 * _CART + 3 * n,
            (Quantity.TCP_SPEED, Source.COMMAND): 2 * _CART + 4 * n,
            (Quantity.TCP_SPEED, Source.FEEDBACK): 2 * _CART + 4 * n + 1,
        }
        pulses = 2 * _CART + 4 * n + 2
        src, scale, div, offset, is_pulse = [], [], [], [], []
        regs: list[int] = []
        word_of: list[tuple[int, bool]] = []  # (output number, high word?)
        uses = set()
        for i, o in enumerate(table.outputs):
            uses.add((o.quantity, o.source))
            pulse = o.quantity in (Quantity.PULSE_1, Quantity.PULSE_2)
            if pulse:
                src.append(pulses + (0 if o.source is Source.COMMAND else n) + o.index)
                scale.append(0.0 if o.forced_zero else 1.0)
                div.append(float(o.resolution))
                offset.append(0 if o.forced_zero else o.offset)
            else:
                src.append(base[(o.quantity, o.source)] + o.index)
                linear = o.quantity is not Quantity.CARTESIAN and axes[o.index].linear
                scale.append(unit_scale(o.quantity, o.index, o.four_bytes, linear))
                div.append(1.0)
                offset.append(0)
            is_pulse.append(pulse)
            regs.append(o.register)
            word_of.append((i, False))
            if o.four_bytes:
                regs.append(o.register + 1)
                word_of.append((i, True))
        # A register named twice keeps the later word: resolve that once, here.
        last = {r: k for k, r in enumerate(regs)}
        keep = sorted(last.values())
        self.src = np.array(src, dtype=np.intp)
        self.scale = np.array(scale)
        self.div = np.array(div)
        self.offset = np.array(offset, dtype=np.int64)
        self.is_pulse = np.array(is_pulse, dtype=bool)
        self.registers = np.array([regs[k] for k in keep], dtype=np.intp)
        self.word_output = np.array([word_of[k][0] for k in keep], dtype=np.intp)
        self.word_high = np.array([word_of[k][1] for k in keep], dtype=bool)
        self.size = pulses + 2 * n
        self.kinematics = any(q in (Quantity.CARTESIAN, Quantity.TCP_SPEED) for q, _ in uses)
        self.feedback = any(s is Source.FEEDBACK for _, s in uses)
        self.speeds = any(q in (Quantity.AXIS_SPEED, Quantity.TCP_SPEED) for q, _ in uses)
        self.rest_key: tuple[int, tuple[int, ...]] | None = None
        self.rest_words: npt.NDArray[np.int64] | None = None

    def words(self, values: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]:
        """The register words (in ``registers`` order) for a value vector."""
        x = values[self.src] * self.scale / self.div
        # Nearest, half away from zero; pulse outputs truncate their division (C ints).
        rounded = np.where(self.is_pulse, np.trunc(x), np.trunc(x + np.copysign(0.5, x)))
        ints = rounded.astype(np.int64) + self.offset
        per_word = ints[self.word_output]
        words: npt.NDArray[np.int64] = np.where(self.word_high, per_word >> 16, per_word) & 0xFFFF
        return words


_Captured = tuple[int, bool, Sequence[ServoGroup], list[tuple[ServoState, int]]]
"""A tick's inputs: tick count, drives powered, the servos, and per plan (in order) its
servo's state and its group's tool."""


class HasTool(Protocol):
    """A group's interpolator: the tool selected for what it executes."""

    tool: int


class RegisterOutputs:
    """Every group's S1CxG outputs in the M-registers, as they are after the latest tick.

    The tick's :meth:`step` keeps the tick's inputs and the words are computed when an
    M-register is next read or written (:meth:`materialise`, the port the IO image is
    built with and calls first on every M-register access, see ``assembly.py``); every
    reader sees the words a controller writing
    them in every tick would show (tests/controller/test_register_outputs_lazy.py)."""

    def __init__(
        self, cell: CellConfig, mregisters: array[int], tcp: TcpTracker, period_ms: int
    ) -> None:
        """``mregisters``: the M-register words this part writes, shared with the IO
        image (:func:`~pymotoros.controller.io_image.mregister_words`)."""
        self._plans = [
            _Plan(cell, g, table)
            for g, table in enumerate(cell.s1cxg)
            if table is not None and table.outputs
        ]
        self._mreg = np.frombuffer(mregisters, dtype=np.uint16)
        self._tcp = tcp
        self._period_s = period_ms / _MS_PER_S
        self._quiet_feedback = cell.servo.noise_pulses == 0
        """Without encoder noise a group at rest has constant outputs (see _write)."""
        self._groups = [plan.index for plan in self._plans]
        self._pending: _Captured | None = None
        """The latest tick's inputs, not yet written."""

    @property
    def active(self) -> bool:
        return bool(self._plans)

    def values(
        self, plan: _Plan, servo: ServoGroup, tool: int, tick: int, powered: bool
    ) -> npt.NDArray[np.float64]:
        """The value vector of ``plan`` from the servo's state now (SI units, pulses).

        Plain Python lists for the few per-axis values (cheaper than numpy at n ≤ 8),
        one array at the end."""
        n = plan.num_axes
        ppu = plan.ppu_list
        cmd = servo.command[:n]
        fb = servo.feedback(tick, powered)[:n] if plan.feedback else cmd
        pos_cmd = [c / f for c, f in zip(cmd, ppu, strict=True)]
        pos_fb = [c / f for c, f in zip(fb, ppu, strict=True)]
        per_s = 1.0 / self._period_s
        zeros = [0.0] * n
        step_cmd, spd_fb = zeros, zeros
        if plan.speeds:
            inc = servo.last_increment
            step_cmd = [inc[k] / ppu[k] for k in range(n)]
            speed = servo.speed()
            spd_fb = [speed[k] / ppu[k] for k in range(n)]
        cart_cmd = cart_fb = [0.0] * _CART
        tcp_cmd = tcp_fb = 0.0
        if plan.kinematics:
            chain = self._tcp.chain(plan.index, tool)
            if chain is not None:
                slots = plan.ros_slot_list
                if plan.identity:
                    q_cmd, q_fb = np.array(pos_cmd), np.array(pos_fb)
                else:
                    q_cmd = np.array([pos_cmd[s] for s in slots])
                    q_fb = np.array([pos_fb[s] for s in slots])
                m_cmd = chain.fk(q_cmd, "tcp", "base_link")
                m_fb = chain.fk(q_fb, "tcp", "base_link")
                e = plan.e_slot
                cart_cmd = [*matrix_to_pose(m_cmd), pos_cmd[e] if e is not None else 0.0]
                cart_fb = [*matrix_to_pose(m_fb), pos_fb[e] if e is not None else 0.0]
                cart_cmd[2] -= chain.base_height
                cart_fb[2] -= chain.base_height
                if plan.speeds:
                    # Distance the TCP moved over one step of the joints, over the period.
                    d_cmd = np.array([step_cmd[s] for s in slots])
                    d_fb = np.array([spd_fb[s] for s in slots]) * self._period_s
                    p0 = chain.position(q_cmd - d_cmd)
                    tcp_cmd = math.dist(m_cmd[:3, 3].tolist(), p0.tolist()) * per_s
                    p0 = chain.position(q_fb - d_fb)
                    tcp_fb = math.dist(m_fb[:3, 3].tolist(), p0.tolist()) * per_s
        return np.array(
            [
                *cart_cmd,
                *cart_fb,
                *pos_cmd,
                *pos_fb,
                *(x * per_s for x in step_cmd),
                *spd_fb,
                tcp_cmd,
                tcp_fb,
                *cmd,
                *fb,
            ],
            dtype=np.float64,
        )

    def step(
        self,
        servos: Sequence[ServoGroup],
        interpolators: Sequence[HasTool],
        tick: int,
        powered: bool,
    ) -> None:
        """The tick's step: keep the servos' state and the tools now, a few tuples per
        group, for :meth:`materialise`.

        Only the latest tick's words can ever be read (each tick writes every output
        register again), so a tick replaces the inputs it kept before."""
        kept = [(servos[g].state(), interpolators[g].tool) for g in self._groups]
        self._pending = (tick, powered, servos, kept)

    def materialise(self) -> None:
        """Write the words of the latest tick's kept inputs (nothing if written).

        Called before any M-register access, so a client's write lands on the tick's
        words and stays until the next tick, and every reader sees what an eager tick
        would have left."""
        pending = self._pending
        if pending is None:
            return
        self._pending = None
        tick, powered, servos, kept = pending
        for plan, (state, tool) in zip(self._plans, kept, strict=True):
            self._write(plan, servos[plan.index].as_of(state), tool, tick, powered)

    def _write(self, plan: _Plan, servo: ServoGroup, tool: int, tick: int, powered: bool) -> None:
        """Compute and write one group's outputs from ``servo``'s state.

        A group at rest (no increment in the feedback window, no feedback noise) has the
        same values whenever its tool and command are the same: its words are rewritten
        from the last computation (a client may have written over them) instead of
        recomputed. Those words are a function of (tool, command) alone, so it does not
        matter at which tick they were computed."""
        key = None
        if self._quiet_feedback and servo.settled():
            key = (tool, tuple(servo.command[: plan.num_axes]))
            if key == plan.rest_key and plan.rest_words is not None:
                self._mreg[plan.registers] = plan.rest_words
                return
        words = plan.words(self.values(plan, servo, tool, tick, powered))
        self._mreg[plan.registers] = words
        plan.rest_key, plan.rest_words = key, words if key is not None else None
