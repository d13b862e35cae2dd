"""Yaskawa controller models as data: interpolation period, groups, byte order, IO map.

Sources (see ``shared/reference``): motoros-1.9.12.md §1.1 (byte order), §2.1
(group caps), §6.2 (IO ranges), §11 (floating-point behaviour of each build);
robot-models.md §3.1 (interpolation periods: the generic "usually 4 ms" figure,
no controller-specific public number exists).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Final

from pymotoros.errors import ConfigError
from pymotoros.protocol.constants import ByteOrder


class ControllerType(enum.StrEnum):
    """Controller families MotoROS 1.9.12 ships a binary for."""

    DX100 = "dx100"
    FS100 = "fs100"
    DX200 = "dx200"
    YRC1000 = "yrc1000"
    YRC1000MICRO = "yrc1000micro"


class FloatMode(enum.Enum):
    """How a controller build evaluates float expressions (§11)."""

    X87_EXTENDED = "x87"
    """x86 builds: every statement in 80-bit extended precision, rounded to float32 on store."""

    STRICT_SINGLE = "single"
    """FS100 (PowerPC e500v2): every operation rounded to float32."""


class IoArea(enum.Enum):
    """The address areas of a Yaskawa IO map (§6.2)."""

    GENERAL_INPUT = "general input"
    GENERAL_OUTPUT = "general output"
    EXTERNAL_INPUT = "external input"
    NETWORK_INPUT = "network input"
    EXTERNAL_OUTPUT = "external output"
    NETWORK_OUTPUT = "network output"
    SPECIFIC_INPUT = "specific input"
    SPECIFIC_OUTPUT = "specific output"
    INTERFACE_PANEL = "interface panel"
    AUXILIARY_RELAY = "auxiliary relay"
    CONTROL_STATUS = "control status"
    PSEUDO_INPUT = "pseudo input"


WRITABLE_AREAS: Final = frozenset(
    {IoArea.GENERAL_OUTPUT, IoArea.NETWORK_INPUT, IoArea.INTERFACE_PANEL}
)
"""Areas MotoROS lets a client write (§6.2); everything else is read-only."""

M_REGISTER_BASE: Final = 1_000_000
"""M-register numbers are offset by one million on the wire (§6.1)."""

M_REGISTER_COUNT: Final = 1000
"""M000..M999 are readable."""

M_REGISTER_WRITABLE: Final = 560
"""M000..M559 are writable (§6.1)."""


@dataclass(frozen=True, slots=True)
class IoRange:
    """An inclusive range of bit addresses; the last decimal digit of each is the bit (0..7)."""

    area: IoArea
    first: int
    last: int

    @property
    def writable(self) -> bool:
        return self.area in WRITABLE_AREAS

    def contains(self, address: int) -> bool:
        return self.first <= address <= self.last and address % 10 <= 7


@dataclass(frozen=True, slots=True)
class ControllerModel:
    """Everything that differs between controller families."""

    type: ControllerType
    interpolation_period_ms: int
    max_groups: int
    byte_order: ByteOrder
    float_mode: FloatMode
    io_ranges: tuple[IoRange, ...]
    pfl_signals: bool
    """YRC1000 / YRC1000micro builds read the PFL signals 81702/81703/15120/15124/15125."""
    skillsnd: bool
    """DX100 only: motion needs the SKILLSND "ROS-START" flag(s) (§4.3)."""
    sets_jog_tool: bool
    """SELECT_TOOL also sets the pendant's jog tool, except on FS100 (§5.8)."""

    def io_range(self, address: int) -> IoRange | None:
        """The range holding ``address`` (bit address), or None."""
        for rng in self.io_ranges:
            if rng.contains(address):
                return rng
        return None


_IoTable = dict[IoArea, tuple[int, int]]

# §6.2 of the reference: the YRC1000's map in full, then each controller as its
# differences from the one it is closest to (the reference's columns, read across).
_YRC1000_IO: Final[_IoTable] = {
    IoArea.GENERAL_INPUT: (10, 5127),
    IoArea.GENERAL_OUTPUT: (10010, 15127),
    IoArea.EXTERNAL_INPUT: (20010, 25127),
    IoArea.NETWORK_INPUT: (27010, 29567),
    IoArea.EXTERNAL_OUTPUT: (30010, 35127),
    IoArea.NETWORK_OUTPUT: (37010, 39567),
    IoArea.SPECIFIC_INPUT: (40010, 42567),
    IoArea.SPECIFIC_OUTPUT: (50010, 55127),
    IoArea.INTERFACE_PANEL: (60010, 60647),
    IoArea.AUXILIARY_RELAY: (70010, 79997),
    IoArea.CONTROL_STATUS: (80010, 85127),
    IoArea.PSEUDO_INPUT: (87010, 87207),
}
_YRC1000MICRO_IO: Final[_IoTable] = _YRC1000_IO | {
    IoArea.EXTERNAL_INPUT: (20010, 21287),
    IoArea.EXTERNAL_OUTPUT: (30010, 31287),
}
_DX200_IO: Final[_IoTable] = _YRC1000_IO | {
    IoArea.SPECIFIC_INPUT: (40010, 41607),
    IoArea.SPECIFIC_OUTPUT: (50010, 53007),
    IoArea.CONTROL_STATUS: (80010, 82007),
    IoArea.PSEUDO_INPUT: (82010, 82207),
}
_DX100_IO: Final[_IoTable] = _DX200_IO | {
    IoArea.GENERAL_INPUT: (10, 2567),
    IoArea.GENERAL_OUTPUT: (10010, 12567),
    IoArea.EXTERNAL_INPUT: (20010, 22567),
    IoArea.NETWORK_INPUT: (25010, 27567),
    IoArea.EXTERNAL_OUTPUT: (30010, 32567),
    IoArea.NETWORK_OUTPUT: (35010, 37567),
    IoArea.SPECIFIC_OUTPUT: (50010, 52007),
    IoArea.CONTROL_STATUS: (80010, 80647),
}
_FS100_IO: Final[_IoTable] = _DX100_IO | {
    IoArea.GENERAL_INPUT: (10, 1287),
    IoArea.GENERAL_OUTPUT: (10010, 11287),
    IoArea.EXTERNAL_INPUT: (20010, 21287),
    IoArea.NETWORK_INPUT: (25010, 26287),
    IoArea.EXTERNAL_OUTPUT: (30010, 31287),
    IoArea.NETWORK_OUTPUT: (35010, 36287),
}

# Interpolation period: 4 ms everywhere, the generic Yaskawa figure (robot-models.md §3.1).
# max_groups: MotoROS caps at 3 on DX100 and 4 elsewhere (§2.1).
# type, max groups, byte order, float mode, IO map, pfl_signals, skillsnd, sets_jog_tool
_LE, _BE = ByteOrder.LITTLE, ByteOrder.BIG
_X87, _SINGLE = FloatMode.X87_EXTENDED, FloatMode.STRICT_SINGLE
_FAMILIES: Final[
    tuple[tuple[ControllerType, int, ByteOrder, FloatMode, _IoTable, bool, bool, bool], ...]
] = (
    (ControllerType.DX100, 3, _LE, _X87, _DX100_IO, False, True, True),
    (ControllerType.FS100, 4, _BE, _SINGLE, _FS100_IO, False, False, False),
    (ControllerType.DX200, 4, _LE, _X87, _DX200_IO, False, False, True),
    (ControllerType.YRC1000, 4, _LE, _X87, _YRC1000_IO, True, False, True),
    (ControllerType.YRC1000MICRO, 4, _LE, _X87, _YRC1000MICRO_IO, True, False, True),
)
CONTROLLERS: Final[dict[ControllerType, ControllerModel]] = {
    kind: ControllerModel(
        kind,
        4,
        groups,
        order,
        floats,
        tuple(IoRange(area, first, last) for area, (first, last) in io.items()),
        pfl_signals=pfl,
        skillsnd=skillsnd,
        sets_jog_tool=jog_tool,
    )
    for kind, groups, order, floats, io, pfl, skillsnd, jog_tool in _FAMILIES
}

DEFAULT_CONTROLLER: Final = ControllerType.YRC1000


def controller_model(name: str | ControllerType) -> ControllerModel:
    """Look a controller up by name (case-insensitive); a clear error lists the known ones."""
    try:
        return CONTROLLERS[ControllerType(str(name).lower())]
    except ValueError:
        known = ", ".join(t.value for t in ControllerType)
        raise ConfigError(f"unknown controller {name!r}; known controllers: {known}") from None
