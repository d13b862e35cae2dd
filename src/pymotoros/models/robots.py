"""Robot models as data: groups, joints (ROS order), limits, pulse ratios, speeds.

Joint names, limits and datasheet speeds come from the ROS-Industrial support
packages as summarised in ``shared/reference/robot-models.md`` §1. Yaskawa does not
publish pulse ratios or the maximum-increment parameters of these arms
(robot-models.md §3.3 and §6), so those are *chosen*: pulses per degree inside the
450–2000 band users measured on DX200 arms, and the maximum pulse rate equal to
the datasheet joint speed, so that MotoROS's speed limit (derived from the maximum
increment per tick, §5.5) lands on the datasheet speed. Each choice is commented
where it is made.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Final

from pymotoros.errors import ConfigError


class GroupKind(enum.Enum):
    """What a control group moves; decides its name prefix and whether it takes tools."""

    ROBOT = "R"
    BASE = "B"
    STATION = "S"


@dataclass(frozen=True, slots=True)
class AxisModel:
    """One joint, in ROS units (rad, or m for a linear axis)."""

    name: str
    lower: float
    upper: float
    max_velocity: float
    """Datasheet speed, rad/s (m/s): what a planner should respect."""
    pulses_per_unit: float
    """Encoder pulses per rad (per m for linear axes): the controller's PtoR / PtoM."""
    max_acceleration: float
    """rad/s² used by the client's motion generator; Yaskawa publishes none (chosen)."""
    max_jerk: float
    """rad/s³ used by the client's motion generator (chosen)."""
    linear: bool = False

    @property
    def max_pulse_rate(self) -> float:
        """The axis's maximum speed in pulses/s, as the controller parameter holds it."""
        return self.max_velocity * self.pulses_per_unit

    def max_increment(self, period_ms: int) -> int:
        """Maximum pulses per interpolation tick: trunc(rate × period × 0.001) (§5.5)."""
        return int(self.max_pulse_rate * period_ms * 0.001)


@dataclass(frozen=True, slots=True)
class DhLink:
    """One link of the GET_DH_PARAMETERS reply: theta, d, a, alpha (rad, m)."""

    theta: float
    d: float
    a: float
    alpha: float


@dataclass(frozen=True, slots=True)
class GroupModel:
    """One control group (R1, B1, S1 …) with its axes in ROS order."""

    name: str
    kind: GroupKind
    axes: tuple[AxisModel, ...]
    moto_slots: tuple[int, ...]
    """Controller slot (0..7) of each ROS-order axis: identity for 6 axes; for a 7-axis arm
    (ROS S,L,E,U,R,B,T; controller S,L,U,R,B,T,E) it is (0, 1, 6, 2, 3, 4, 5) (§5.7)."""
    home: tuple[float, ...]
    """The built-in ``home`` pose, ROS order."""
    dh: tuple[DhLink, ...] = field(default=())
    """Up to 8 DH links for GET_DH_PARAMETERS."""

    def __post_init__(self) -> None:
        n = len(self.axes)
        if not 1 <= n <= 8:
            raise ConfigError(f"group {self.name}: {n} axes, a group has 1..8")
        if len(self.moto_slots) != n or len(set(self.moto_slots)) != n:
            raise ConfigError(f"group {self.name}: moto_slots must map each of {n} axes once")
        if any(not 0 <= s < 8 for s in self.moto_slots):
            raise ConfigError(f"group {self.name}: moto_slots must lie in 0..7")
        if len(self.home) != n:
            raise ConfigError(f"group {self.name}: home needs {n} values")
        if len(self.dh) > 8:
            raise ConfigError(f"group {self.name}: at most 8 DH links")

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def num_axes(self) -> int:
        return len(self.axes)


@dataclass(frozen=True, slots=True)
class RobotModel:
    """A robot as the controller sees it: one or more control groups."""

    name: str
    description: str
    groups: tuple[GroupModel, ...]
    controllers: frozenset[str]
    """Controller families this robot is really sold with (others get a warning)."""


def _deg(x: float) -> float:
    return math.radians(x)


def _ppr(pulses_per_degree: float) -> float:
    """Pulses per radian from pulses per degree."""
    return pulses_per_degree * 180.0 / math.pi


def _six_axis_slots() -> tuple[int, ...]:
    return (0, 1, 2, 3, 4, 5)


# HC10 (A0) and HC10DT (A1): limits and speeds from robot-models.md §1.2 (manuals HW1483896,
# HW1485083). Pulses/degree chosen (no public value): 1435 for the big S/L axes (the MA1440
# S-axis figure measured by users, robot-models.md §3.3), smaller ratios towards the wrist
# as on every measured Motoman arm. Accelerations/jerks chosen conservatively for a cobot:
# about 2.5× the joint speed per second, jerk 10× the acceleration per second.
_HC10_AXES: Final = (
    AxisModel("joint_1_s", -math.pi, math.pi, _deg(130), _ppr(1435.0), 5.5, 55.0),
    AxisModel("joint_2_l", -math.pi, math.pi, _deg(130), _ppr(1435.0), 5.5, 55.0),
    AxisModel("joint_3_u", _deg(-5), _deg(355), _deg(180), _ppr(1250.0), 7.5, 75.0),
    AxisModel("joint_4_r", -math.pi, math.pi, _deg(180), _ppr(910.0), 7.5, 75.0),
    AxisModel("joint_5_b", -math.pi, math.pi, _deg(250), _ppr(910.0), 10.5, 105.0),
    AxisModel("joint_6_t", -math.pi, math.pi, _deg(250), _ppr(650.0), 10.5, 105.0),
)

HC10: Final = RobotModel(
    name="hc10",
    description="Yaskawa HC10 (A0) collaborative robot, 10 kg, 6 axes",
    groups=(
        GroupModel(
            name="R1",
            kind=GroupKind.ROBOT,
            axes=_HC10_AXES,
            moto_slots=_six_axis_slots(),
            home=(0.0,) * 6,
            # Standard DH read off the URDF origins of robot-models.md §1.2 (derived):
            # S at 0.275 m, L→U 0.700 m, U→B 0.500 m, B→flange offset 0.162 m, flange 0.130 m.
            dh=(
                DhLink(0.0, 0.275, 0.0, -math.pi / 2),
                DhLink(-math.pi / 2, 0.0, 0.700, 0.0),
                DhLink(0.0, 0.0, 0.0, math.pi / 2),
                DhLink(0.0, 0.500, 0.0, -math.pi / 2),
                DhLink(0.0, 0.162, 0.0, math.pi / 2),
                DhLink(0.0, 0.130, 0.0, 0.0),
            ),
        ),
    ),
    controllers=frozenset({"yrc1000", "yrc1000micro"}),
)

ROBOTS: Final[dict[str, RobotModel]] = {HC10.name: HC10}
"""Every built-in robot, by lower-case name."""

DEFAULT_ROBOT: Final = "hc10"


def robot_model(name: str) -> RobotModel:
    """Look a robot up by name (case-insensitive); a clear error lists the known ones."""
    try:
        return ROBOTS[name.lower()]
    except KeyError:
        known = ", ".join(sorted(ROBOTS))
        raise ConfigError(f"unknown robot {name!r}; known robots: {known}") from None
