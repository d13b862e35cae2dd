"""The S1CxG register output functions (seed 003 Appendix A, manual §6.12), as rules.

A YRC1000 can copy, every interpolation period, the manipulator's Cartesian position, its
pulse positions, its TCP speed and each axis's speed and position into M-registers, which
a client then reads over the IO port. Which values go where is set by the S1CxG
parameters of each control group; this module holds those parameters
(:class:`S1cxgTable`), every rule of the seed about them, the list of register words they
produce (:attr:`S1cxgTable.outputs`), the encoding of a value into register words and the
decoding back (for the client). Pure and numpy-free: shared by the controller (which
computes the values) and the client (which reads them).

Rules (each with its seed sentence in docs/cell.md):

* 2-byte outputs hold the lower 16 bits of the value in two's complement; 4-byte outputs
  put the lower word at the register and the upper word at the next one.
* Register number 0 means "no output": M000 is never written.
* A register named twice holds the value written later, in the order of
  :attr:`S1cxgTable.outputs` (the seed's sections in order, command before feedback,
  axes in order).
* In the pulse position functions an axis enabled for both command and feedback outputs 0.
* Resolution 0 counts as 1; the pulse output is pulse / resolution + offset (the division
  truncates towards zero, as the controller's C integer division).
* Units by size: Cartesian X, Y, Z in mm (2 bytes) or µm (4 bytes), Rx, Ry, Rz, Re in deg
  or 0.0001 deg (the seed's own example says 0.001 deg for 4 bytes; its parameter notes
  say 0.0001 deg, which we follow, docs/fidelity.md); TCP speed mm/s or µm/s; axis speed
  deg/s or 0.0001 deg/s (mm/s or µm/s for a linear axis); axis position deg or 0.0001
  deg (mm or µm). Re is 0 on a 6-axis arm (it is the 7-axis arms' elbow angle).
* Floating values are rounded to the nearest unit (half away from zero).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Final

from pymotoros.errors import ConfigError
from pymotoros.models.controllers import M_REGISTER_COUNT

WORD_MASK: Final = 0xFFFF
"""An M-register holds 16 bits."""
MAX_AXES: Final = 8
"""A control group has up to 8 axes: the per-axis parameters come in eights."""
MAX_OFFSET: Final = 2**31 - 1
"""The offset parameters are 32-bit signed values."""


class Quantity(enum.Enum):
    """What a register output holds."""

    CARTESIAN = "cartesian"
    PULSE_1 = "pulse_1"
    PULSE_2 = "pulse_2"
    TCP_SPEED = "tcp_speed"
    AXIS_SPEED = "axis_speed"
    AXIS_POSITION = "axis_position"


class Source(enum.Enum):
    COMMAND = "command"
    FEEDBACK = "feedback"


CARTESIAN_NAMES: Final = ("x", "y", "z", "rx", "ry", "rz", "re")


@dataclass(frozen=True, slots=True)
class Output:
    """One value the table sends to registers: ``register`` (and ``register + 1`` when
    ``four_bytes``). ``index`` is the coordinate (0..6: X, Y, Z, Rx, Ry, Rz, Re) or the
    axis (0..7, controller order S, L, U, R, B, T, E, 8th)."""

    quantity: Quantity
    source: Source
    index: int
    register: int
    four_bytes: bool
    resolution: int = 1
    offset: int = 0
    forced_zero: bool = False
    """Pulse functions: the axis is enabled for command and feedback, so 0 is output."""

    @property
    def registers(self) -> tuple[int, ...]:
        return (self.register, self.register + 1) if self.four_bytes else (self.register,)


def words(value: int, four_bytes: bool) -> tuple[int, ...]:
    """The register words of an integer value: lower 16 bits (two's complement), and with
    ``four_bytes`` the next 16 bits in the following register."""
    low = value & WORD_MASK
    return (low, (value >> 16) & WORD_MASK) if four_bytes else (low,)


def from_words(low: int, high: int | None = None) -> int:
    """The signed value of one (16-bit) or two (32-bit, lower word first) register words."""
    if high is None:
        v = low & WORD_MASK
        return v - 0x10000 if v & 0x8000 else v
    v = (low & WORD_MASK) | ((high & WORD_MASK) << 16)
    return v - 0x1_0000_0000 if v & 0x8000_0000 else v


def unit_scale(quantity: Quantity, index: int, four_bytes: bool, linear: bool = False) -> float:
    """Register units per SI unit (m, rad, m/s, rad/s) of an output (seed units)."""
    deg = 180.0 / math.pi
    if quantity is Quantity.CARTESIAN:
        if index < 3:
            return 1e6 if four_bytes else 1e3
        return deg * (1e4 if four_bytes else 1.0)
    if quantity is Quantity.TCP_SPEED:
        return 1e6 if four_bytes else 1e3
    if quantity in (Quantity.AXIS_SPEED, Quantity.AXIS_POSITION):
        if linear:
            return 1e6 if four_bytes else 1e3
        return deg * (1e4 if four_bytes else 1.0)
    return 1.0  # pulses


# Parameter numbers (seed Appendix A).
P_CART_CMD_ENABLE: Final = 208
P_CART_CMD_SIZE: Final = 209
P_CART_CMD_REG: Final = 210  # 210..216: X, Y, Z, Rx, Ry, Rz, Re
P_CART_FB_ENABLE: Final = 217
P_CART_FB_SIZE: Final = 218
P_CART_FB_REG: Final = 219  # 219..225 (the seed's table prints 224 twice; 225 is Re)
P_PULSE1_CMD: Final = 202
P_PULSE1_FB: Final = 203
P_PULSE1_SIZE: Final = 204
P_PULSE2_CMD: Final = 205
P_PULSE2_FB: Final = 206
P_PULSE2_SIZE: Final = 207
P_PULSE1_REG: Final = 1090
P_PULSE1_RES: Final = 1100
P_PULSE1_OFS: Final = 1110
P_PULSE2_REG: Final = 1120
P_PULSE2_RES: Final = 1130
P_PULSE2_OFS: Final = 1140
P_TCP_CMD_MODE: Final = 330
P_TCP_CMD_REG: Final = 331
P_TCP_FB_MODE: Final = 332
P_TCP_FB_REG: Final = 333
P_AXIS_SPEED_CMD: Final = 334
P_AXIS_SPEED_FB: Final = 335
P_AXIS_SPEED_CMD_REG: Final = 1270
P_AXIS_SPEED_FB_REG: Final = 1280
P_AXIS_POS_CMD: Final = 336
P_AXIS_POS_FB: Final = 337
P_AXIS_POS_CMD_REG: Final = 1290
P_AXIS_POS_FB_REG: Final = 1300

_MAX_REGISTER: Final = M_REGISTER_COUNT - 1
_CART_COORDS: Final = 7

_AXIS_MASKS: Final = (
    P_PULSE1_CMD,
    P_PULSE1_FB,
    P_PULSE1_SIZE,
    P_PULSE2_CMD,
    P_PULSE2_FB,
    P_PULSE2_SIZE,
)
"""The parameters that hold one bit per axis (which axes a pulse output covers)."""
_AXIS_REGISTERS: Final = (
    P_PULSE1_REG,
    P_PULSE2_REG,
    P_AXIS_SPEED_CMD_REG,
    P_AXIS_SPEED_FB_REG,
    P_AXIS_POS_CMD_REG,
    P_AXIS_POS_FB_REG,
)
"""The first of the per-axis register parameters: axis k's register is ``base + k``."""


def _parameter_ranges() -> dict[int, tuple[int, int, str]]:
    """Every known parameter: (lowest, highest value, what it is)."""
    r: dict[int, tuple[int, int, str]] = {}
    reg = (0, _MAX_REGISTER, "a register number 0..999 (0: no output)")
    for p in (P_CART_CMD_ENABLE, P_CART_FB_ENABLE):
        r[p] = (0, 1, "0 (disable) or 1 (enable)")
    for p in (P_CART_CMD_SIZE, P_CART_FB_SIZE):
        r[p] = (0, 1, "0 (2 bytes) or 1 (4 bytes)")
    for base in (P_CART_CMD_REG, P_CART_FB_REG):
        for k in range(_CART_COORDS):
            r[base + k] = reg
    for p in _AXIS_MASKS:
        r[p] = (0, 255, "an axis bit mask 0..255")
    for k in range(MAX_AXES):
        for base in _AXIS_REGISTERS:
            r[base + k] = reg
        for base in (P_PULSE1_RES, P_PULSE2_RES):
            r[base + k] = (0, MAX_OFFSET, "a resolution ≥ 0 (0 counts as 1)")
        for base in (P_PULSE1_OFS, P_PULSE2_OFS):
            r[base + k] = (-MAX_OFFSET - 1, MAX_OFFSET, "a 32-bit offset in pulses")
    for p in (P_TCP_CMD_MODE, P_TCP_FB_MODE, P_AXIS_SPEED_CMD, P_AXIS_SPEED_FB):
        r[p] = (0, 2, "0 (no output), 1 (2 bytes) or 2 (4 bytes)")
    for p in (P_AXIS_POS_CMD, P_AXIS_POS_FB):
        r[p] = (0, 2, "0 (no output), 1 (2 bytes) or 2 (4 bytes)")
    for p in (P_TCP_CMD_REG, P_TCP_FB_REG):
        r[p] = reg
    return r


PARAMETERS: Final = _parameter_ranges()
"""Every S1CxG parameter number of Appendix A with its allowed values."""


@dataclass(frozen=True, slots=True)
class S1cxgTable:
    """One group's S1CxG parameters (unset ones are 0, as on a fresh controller).

    Build with :func:`parse_s1cxg` (from a cell file table or a dict), which applies the
    seed's rules and refuses a bad table naming the parameter and the rule.
    """

    params: tuple[tuple[int, int], ...]
    num_axes: int
    robot: bool
    """The group is a manipulator (Cartesian and TCP functions need one)."""
    outputs: tuple[Output, ...] = field(default=())

    def get(self, number: int) -> int:
        return dict(self.params).get(number, 0)

    @property
    def registers(self) -> tuple[int, ...]:
        """Every register written, in order (a register may appear twice)."""
        return tuple(r for o in self.outputs for r in o.registers)


def _outputs(p: Mapping[int, int], num_axes: int) -> list[Output]:
    out: list[Output] = []

    def reg_ok(number: int) -> bool:
        return number != 0

    for enable, size, base, source in (
        (P_CART_CMD_ENABLE, P_CART_CMD_SIZE, P_CART_CMD_REG, Source.COMMAND),
        (P_CART_FB_ENABLE, P_CART_FB_SIZE, P_CART_FB_REG, Source.FEEDBACK),
    ):
        if p.get(enable, 0):
            four = p.get(size, 0) == 1
            for k in range(_CART_COORDS):
                reg = p.get(base + k, 0)
                if reg_ok(reg):
                    out.append(Output(Quantity.CARTESIAN, source, k, reg, four))
    for quantity, cmd_p, fb_p, size_p, reg_p, res_p, ofs_p in (
        (Quantity.PULSE_1, P_PULSE1_CMD, P_PULSE1_FB, P_PULSE1_SIZE, P_PULSE1_REG, P_PULSE1_RES,
         P_PULSE1_OFS),
        (Quantity.PULSE_2, P_PULSE2_CMD, P_PULSE2_FB, P_PULSE2_SIZE, P_PULSE2_REG, P_PULSE2_RES,
         P_PULSE2_OFS),
    ):  # fmt: skip
        cmd, fb, size = p.get(cmd_p, 0), p.get(fb_p, 0), p.get(size_p, 0)
        for k in range(num_axes):
            bit = 1 << k
            if not (cmd | fb) & bit:
                continue
            reg = p.get(reg_p + k, 0)
            if not reg_ok(reg):
                continue
            both = bool(cmd & bit and fb & bit)
            out.append(
                Output(
                    quantity,
                    Source.COMMAND if cmd & bit else Source.FEEDBACK,
                    k,
                    reg,
                    bool(size & bit),
                    resolution=p.get(res_p + k, 0) or 1,
                    offset=p.get(ofs_p + k, 0),
                    forced_zero=both,
                )
            )
    for mode_p, reg_p, source in (
        (P_TCP_CMD_MODE, P_TCP_CMD_REG, Source.COMMAND),
        (P_TCP_FB_MODE, P_TCP_FB_REG, Source.FEEDBACK),
    ):
        mode, reg = p.get(mode_p, 0), p.get(reg_p, 0)
        if mode and reg_ok(reg):
            out.append(Output(Quantity.TCP_SPEED, source, 0, reg, mode == 2))
    for quantity, funcs in (
        (
            Quantity.AXIS_SPEED,
            (
                (P_AXIS_SPEED_CMD, P_AXIS_SPEED_CMD_REG, Source.COMMAND),
                (P_AXIS_SPEED_FB, P_AXIS_SPEED_FB_REG, Source.FEEDBACK),
            ),
        ),
        (
            Quantity.AXIS_POSITION,
            (
                (P_AXIS_POS_CMD, P_AXIS_POS_CMD_REG, Source.COMMAND),
                (P_AXIS_POS_FB, P_AXIS_POS_FB_REG, Source.FEEDBACK),
            ),
        ),
    ):
        for mode_p, reg_p, source in funcs:
            mode = p.get(mode_p, 0)
            if not mode:
                continue
            for k in range(num_axes):
                reg = p.get(reg_p + k, 0)
                if reg_ok(reg):
                    out.append(Output(quantity, source, k, reg, mode == 2))
    return out


def parse_s1cxg(
    data: Mapping[str, object] | Mapping[int, object],
    *,
    num_axes: int,
    robot: bool = True,
    where: str = "s1cxg",
) -> S1cxgTable:
    """An S1CxG table from ``{parameter number: value}`` (keys as TOML gives them, "208",
    or ints). Refuses, naming the parameter and the rule: an unknown parameter number, a
    value that is not an integer or out of range, a Cartesian function enabled without all
    its register numbers (the seed: "be sure to set..."), a Cartesian or TCP function on a
    group that is not a manipulator, a 4-byte output at M999 (no next register), and an
    axis bit or register for an axis the group does not have."""
    params: dict[int, int] = {}
    for key, value in data.items():
        text = str(key)
        if not text.isdigit():
            raise ConfigError(f"{where}: {key!r} is not an S1CxG parameter number (e.g. 208)")
        number = int(text)
        if number not in PARAMETERS:
            raise ConfigError(
                f"{where}.{number}: no such S1CxG parameter (Appendix A: 202-225, 330-337, "
                "1090-1147, 1270-1307)"
            )
        if not isinstance(value, int) or isinstance(value, bool):
            raise ConfigError(f"{where}.{number}: must be an integer, not {value!r}")
        lo, hi, what = PARAMETERS[number]
        if not lo <= value <= hi:
            raise ConfigError(f"{where}.{number}: must be {what}, not {value}")
        params[number] = value

    def err(number: int, rule: str) -> ConfigError:
        return ConfigError(f"{where}.{number}: {rule}")

    for enable, base in ((P_CART_CMD_ENABLE, P_CART_CMD_REG), (P_CART_FB_ENABLE, P_CART_FB_REG)):
        if params.get(enable):
            if not robot:
                raise err(enable, "the Cartesian position needs a manipulator (robot group)")
            for k in range(_CART_COORDS):
                if base + k not in params:
                    raise err(
                        base + k,
                        f"is required when {enable} = 1: set the register of "
                        f"{CARTESIAN_NAMES[k]} (0 for no output)",
                    )
    for mode in (P_TCP_CMD_MODE, P_TCP_FB_MODE):
        if params.get(mode) and not robot:
            raise err(mode, "the TCP speed needs a manipulator (robot group)")
    for mask in _AXIS_MASKS:
        extra = params.get(mask, 0) >> num_axes
        if extra:
            raise err(mask, f"sets a bit for an axis beyond the group's {num_axes} axes")
    for base in _AXIS_REGISTERS:
        for k in range(num_axes, MAX_AXES):
            if params.get(base + k):
                raise err(base + k, f"names a register for axis {k + 1}; the group has {num_axes}")
    outputs = _outputs(params, num_axes)
    for o in outputs:
        if o.four_bytes and o.register + 1 > _MAX_REGISTER:
            raise ConfigError(
                f"{where}: a 4-byte output at M{o.register:03d} needs M{o.register + 1:03d}, "
                f"which does not exist (M000..M{_MAX_REGISTER:03d})"
            )
    return S1cxgTable(tuple(sorted(params.items())), num_axes, robot, tuple(outputs))


@dataclass(frozen=True, slots=True)
class Reading:
    """One decoded output: what it is, its raw integer and the value in its unit."""

    quantity: Quantity
    source: Source
    index: int
    raw: int
    """The integer in the register unit (``raw_unit``)."""
    value: float
    """In ``unit``: mm, deg, mm/s, deg/s or pulse (4-byte outputs scaled back)."""
    unit: str
    raw_unit: str


def _unit(o: Output, linear: bool) -> str:
    if o.quantity is Quantity.CARTESIAN:
        if o.index < 3:
            return "um" if o.four_bytes else "mm"
        return "0.0001deg" if o.four_bytes else "deg"
    if o.quantity is Quantity.TCP_SPEED:
        return "um/s" if o.four_bytes else "mm/s"
    if o.quantity in (Quantity.AXIS_SPEED, Quantity.AXIS_POSITION):
        base = (
            ("um" if o.four_bytes else "mm") if linear else ("0.0001deg" if o.four_bytes else "deg")
        )
        return base + ("/s" if o.quantity is Quantity.AXIS_SPEED else "")
    return "pulse"


def decode(
    table: S1cxgTable, registers: Mapping[int, int], linear: Sequence[bool] = ()
) -> list[Reading]:
    """The outputs of ``table`` read back from register words (``{number: word}``).

    ``value`` is in the friendly unit: mm, deg, mm/s, deg/s (m-based units for linear
    axes become mm), pulses; ``raw`` the integer in the register unit. An output whose
    register is overwritten by a later output of the same table is skipped (its value
    is gone)."""
    last_writer: dict[int, int] = {}
    for i, o in enumerate(table.outputs):
        for r in o.registers:
            last_writer[r] = i
    out: list[Reading] = []
    for i, o in enumerate(table.outputs):
        if any(last_writer[r] != i for r in o.registers):
            continue
        raw = from_words(registers[o.register], registers[o.register + 1] if o.four_bytes else None)
        is_linear = bool(linear[o.index]) if linear and o.quantity in (
            Quantity.AXIS_SPEED, Quantity.AXIS_POSITION) else False  # fmt: skip
        raw_unit = _unit(o, is_linear)
        unit = _unit(replace(o, four_bytes=False), is_linear)
        value = float(raw)
        if raw_unit != unit:
            value = raw / 1e4 if raw_unit.startswith("0.0001") else raw / 1e3
        out.append(Reading(o.quantity, o.source, o.index, raw, value, unit, raw_unit))
    return out
