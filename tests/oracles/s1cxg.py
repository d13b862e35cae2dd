"""The S1CxG register outputs' reference rule: one output at a time, in plain Python.

The library compiles a group's table into index and scale arrays and computes every
word with a few numpy operations (``pymotoros.controller.registers``). Here is the rule
as the seed's table reads, output by output, that it is compared with
(``tests/controller/test_s1cxg_registers.py``): the value in its unit, rounded half away
from zero (pulse outputs truncate their division), split into 16-bit words.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from pymotoros.models.s1cxg import Output, Quantity, S1cxgTable, Source, unit_scale, words


def _round(value: float) -> int:
    """Nearest integer, half away from zero (not banker's rounding)."""
    return int(math.copysign(math.floor(abs(value) + 0.5), value))


@dataclass(frozen=True, slots=True)
class GroupValues:
    """What the register functions read from one group, in SI units, controller order.

    ``cartesian`` are (x, y, z, rx, ry, rz, re) in m and rad (base coordinates); pulses are
    integers; speeds in rad/s (m/s), positions in rad (m); ``linear`` per axis."""

    cartesian_command: Sequence[float] = ()
    cartesian_feedback: Sequence[float] = ()
    pulse_command: Sequence[int] = ()
    pulse_feedback: Sequence[int] = ()
    tcp_speed_command: float = 0.0
    tcp_speed_feedback: float = 0.0
    axis_speed_command: Sequence[float] = ()
    axis_speed_feedback: Sequence[float] = ()
    axis_position_command: Sequence[float] = ()
    axis_position_feedback: Sequence[float] = ()
    linear: Sequence[bool] = ()


def output_value(o: Output, v: GroupValues) -> int:
    """The integer an output holds for the values ``v`` (before splitting into words)."""
    cmd = o.source is Source.COMMAND
    q = o.quantity
    if q in (Quantity.PULSE_1, Quantity.PULSE_2):
        if o.forced_zero:
            return 0
        pulses = (v.pulse_command if cmd else v.pulse_feedback)[o.index]
        return int(pulses / o.resolution) + o.offset
    linear = bool(v.linear[o.index]) if v.linear and q is not Quantity.CARTESIAN else False
    scale = unit_scale(q, o.index, o.four_bytes, linear)
    value: float
    if q is Quantity.CARTESIAN:
        value = (v.cartesian_command if cmd else v.cartesian_feedback)[o.index]
    elif q is Quantity.TCP_SPEED:
        value = v.tcp_speed_command if cmd else v.tcp_speed_feedback
    elif q is Quantity.AXIS_SPEED:
        value = (v.axis_speed_command if cmd else v.axis_speed_feedback)[o.index]
    else:
        value = (v.axis_position_command if cmd else v.axis_position_feedback)[o.index]
    return _round(value * scale)


def write_outputs(
    table: S1cxgTable, values: GroupValues, write: Callable[[int, int], None]
) -> None:
    """Write every output of ``table`` for ``values`` through ``write(register, word)``,
    in table order (so a register named twice keeps the later value)."""
    for o in table.outputs:
        ws = words(output_value(o, values), o.four_bytes)
        write(o.register, ws[0])
        if o.four_bytes:
            write(o.register + 1, ws[1])
