"""Reading the S1CxG register outputs from the client: one call, typed values.

Given the same S1CxG table as the controller's (the ``[groups.s1cxg]`` table of a cell
file, which is also the documented way to write down a real controller's parameters),
the client reads every register the table fills over the IO port and decodes them with
the rules of :mod:`pymotoros.models.s1cxg`.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from pymotoros.errors import ConfigError
from pymotoros.models.cell import read_cell_file
from pymotoros.models.robots import GroupKind, GroupModel
from pymotoros.models.s1cxg import Quantity, Reading, S1cxgTable, Source, decode, parse_s1cxg


def s1cxg_table(
    source: Mapping[str, object] | str | Path, group: GroupModel, *, index: int = 0
) -> S1cxgTable:
    """The S1CxG table for ``group`` from a ``{"208": 1, ...}`` mapping or a cell file
    (its ``index``-th ``[[groups]]`` entry's ``[groups.s1cxg]``)."""
    where = "s1cxg"
    if isinstance(source, str | Path):
        path = Path(source)
        data = read_cell_file(path).data
        groups = data.get("groups")
        if not isinstance(groups, list) or index >= len(groups):
            raise ConfigError(f"{path}: no [[groups]] entry {index}")
        table = groups[index].get("s1cxg") if isinstance(groups[index], dict) else None
        if not isinstance(table, dict):
            raise ConfigError(f"{path}: groups[{index}] has no [groups.s1cxg] table")
        mapping: Mapping[str, object] = table
        where = f"{path}: groups[{index}].s1cxg"
    else:
        mapping = source
    return parse_s1cxg(
        mapping, num_axes=group.num_axes, robot=group.kind is GroupKind.ROBOT, where=where
    )


@dataclass(frozen=True, slots=True)
class RegisterValues:
    """Decoded register outputs. Missing values (function not configured) are None;
    per-axis tuples hold None for an axis without an output."""

    readings: tuple[Reading, ...]
    words: Mapping[int, int] = field(default_factory=dict)

    def _one(self, quantity: Quantity, source: Source, index: int = 0) -> float | None:
        for r in self.readings:
            if r.quantity is quantity and r.source is source and r.index == index:
                return r.value
        return None

    def tcp_speed_mm_s(self, source: Source = Source.FEEDBACK) -> float | None:
        return self._one(Quantity.TCP_SPEED, source)

    def cartesian(self, source: Source = Source.FEEDBACK) -> tuple[float | None, ...]:
        """X, Y, Z (mm), Rx, Ry, Rz, Re (deg) in base coordinates."""
        return tuple(self._one(Quantity.CARTESIAN, source, k) for k in range(7))

    def axis_speeds(self, source: Source = Source.FEEDBACK) -> tuple[float | None, ...]:
        """deg/s (mm/s for a linear axis), controller axis order."""
        return tuple(self._one(Quantity.AXIS_SPEED, source, k) for k in range(8))

    def axis_positions(self, source: Source = Source.FEEDBACK) -> tuple[float | None, ...]:
        """deg (mm for a linear axis), controller axis order."""
        return tuple(self._one(Quantity.AXIS_POSITION, source, k) for k in range(8))

    def pulses(self, function: int = 1) -> tuple[float | None, ...]:
        """Pulse position function 1 or 2 (pulse / resolution + offset), per axis."""
        quantity = Quantity.PULSE_1 if function == 1 else Quantity.PULSE_2
        out: list[float | None] = []
        for k in range(8):
            found = [r.value for r in self.readings if r.quantity is quantity and r.index == k]
            out.append(found[0] if found else None)
        return tuple(out)


async def read_register_outputs(
    read_mregister: Callable[[int], Awaitable[int]], table: S1cxgTable, model: GroupModel
) -> RegisterValues:
    """Read every register ``table`` fills (one ``read_mregister`` each: the client's
    M-register read) and decode them for the group ``model``."""
    words: dict[int, int] = {}
    for number in sorted(set(table.registers)):
        words[number] = await read_mregister(number)
    slot_axis = {slot: ros for ros, slot in enumerate(model.moto_slots)}
    linear = [model.axes[slot_axis[k]].linear for k in range(model.num_axes)]
    return RegisterValues(tuple(decode(table, words, linear)), words)
