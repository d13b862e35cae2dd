"""Robot models as data: groups, joints (ROS order), limits, pulse ratios, speeds.

Joint names, limits and datasheet speeds come from the ROS-Industrial support
packages as summarised in ``shared/reference/robot-models.md`` §1. Yaskawa does not
publish pulse ratios or the maximum-increment parameters of these arms
(robot-models.md §3.3 and §6), so those are *chosen*: pulses per degree inside the
450–2000 band users measured on DX200 arms, falling from the base to the wrist as on
every measured arm, and the maximum pulse rate (a whole number of pulses/s, as the
controller parameter is) equal to the datasheet joint speed. Each ratio is picked so
that speed × ratio is a whole number of pulses per 4 ms tick: then MotoROS's speed
limit (derived from the maximum increment per tick, §5.5) is the datasheet speed to
the pulse. Each choice is commented where it is made.

A robot model is one declaration, collision shapes included: every robot group (R1,
R2 …) carries its joint geometry and the capsule radii of its links
(:attr:`GroupModel.link_radii`), and :class:`RobotModel` refuses a robot group without
them, because a group without shapes would pass through every obstacle of the cell.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass, field
from typing import Final

from pymotoros.errors import ConfigError
from pymotoros.protocol.messages.dh import DhLink as DhLink  # re-exported: the models use it


class GroupKind(enum.Enum):
    """What a control group moves; decides its name prefix and whether it takes tools."""

    ROBOT = "R"
    BASE = "B"
    STATION = "S"


Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Transform:
    """A fixed transform as URDF writes it: translation (m), then fixed-axis roll, pitch,
    yaw (rad) applied about X, then Y, then Z (R = Rz·Ry·Rx)."""

    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class JointGeometry:
    """Where a joint sits in its parent link (URDF ``origin``) and the axis it turns about,
    in the joint's own frame (URDF ``axis``): the data of robot-models.md §1."""

    origin: Transform
    axis: Vec3


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
    geometry: JointGeometry | None = None
    """Joint origin and axis for the kinematics (None: the group has no kinematic chain)."""

    @property
    def max_pulse_rate(self) -> int:
        """The axis's maximum speed in whole pulses/s, as the controller parameter holds it."""
        return round(self.max_velocity * self.pulses_per_unit)

    def max_increment(self, period_ms: int) -> int:
        """Maximum pulses per interpolation tick: trunc(rate × period × 0.001) (§5.5)."""
        return int(self.max_pulse_rate * period_ms * 0.001)


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
    """Up to 8 DH links for GET_DH_PARAMETERS (theta, d, a, alpha: rad, m), the wire's
    own :class:`~pymotoros.protocol.messages.DhLink`: one type from model to reply."""
    mount: Transform = Transform()
    """Where the first joint's parent link sits in ``base_link`` (SDA10F arms: the torso)."""
    tool0: Transform | None = None
    """``tool0`` in the last link's frame (None: no tool0, the chain ends at the flange)."""
    base_height: float = 0.0
    """Height of the ROS-Industrial ``base`` frame (Yaskawa robot coordinates) above
    ``base_link``: the S-axis height of robot-models.md (0: the two frames coincide)."""
    link_radii: tuple[float, ...] = ()
    """The collision shapes: the capsule radius (m) of the base link, then of each joint's
    link in ROS order (``num_axes + 1`` values). Each link is a capsule around the segment
    from its joint to the next (the last: to ``tool0``; the base link: from ``base_link``
    to the first joint), so the joint origins give the segments and only the radii are
    declared. A robot group must have them (:class:`RobotModel` refuses one without: it
    would pass through obstacles); a base or station axis (the SDA10F torso) has none,
    the arms' base links cover it."""

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
        """The axes' names in ROS order, as in trajectories and joint states."""
        return tuple(a.name for a in self.axes)

    @property
    def num_axes(self) -> int:
        """Number of axes in the group (robot joints or external axes)."""
        return len(self.axes)


@dataclass(frozen=True, slots=True)
class RobotModel:
    """A robot as the controller sees it: one or more control groups."""

    name: str
    description: str
    groups: tuple[GroupModel, ...]
    controllers: frozenset[str]
    """Controller families this robot is really sold with (others get a warning)."""
    pfl: bool = False
    """A collaborative (HC) arm with Power and Force Limiting: on a YRC1000 /
    YRC1000micro it enables MotoROS's PFL option (reference §4.4)."""

    def __post_init__(self) -> None:
        for group in self.groups:
            _check_shapes(self.name, group)


def _check_shapes(robot: str, group: GroupModel) -> None:
    """Refuse a robot group without collision shapes (joint geometry and one capsule
    radius per link), and shapes on a base or station axis, which nothing would use."""
    where = f"robot model {robot!r} group {group.name}"
    n = group.num_axes
    if group.kind is not GroupKind.ROBOT:
        if group.link_radii:
            raise ConfigError(
                f"{where} is a {group.kind.name.lower()} axis group: it takes no link_radii "
                "(only robot groups R1, R2 … have collision shapes)"
            )
        return
    if not group.link_radii:
        raise ConfigError(
            f"{where} has no collision shapes, so obstacles would never stop it: declare "
            f"link_radii on the group, {n + 1} capsule radii in m (the base link's, then "
            "one per joint's link in ROS order)"
        )
    if len(group.link_radii) != n + 1:
        raise ConfigError(
            f"{where}: {len(group.link_radii)} link_radii for {n} axes; give {n + 1} "
            "(the base link's, then one per joint's link in ROS order)"
        )
    for i, r in enumerate(group.link_radii):
        if not (math.isfinite(r) and r > 0):
            raise ConfigError(f"{where}: link_radii[{i}] is {r!r}, a capsule radius is > 0 m")
    unplaced = [a.name for a in group.axes if a.geometry is None]
    if unplaced:
        raise ConfigError(
            f"{where} has no collision shapes: {', '.join(unplaced)} has no geometry "
            "(joint origin and axis), so its links cannot be placed; declare the geometry"
        )


def _deg(x: float) -> float:
    return math.radians(x)


def _ppr(pulses_per_degree: float) -> float:
    """Pulses per radian from pulses per degree."""
    return pulses_per_degree * 180.0 / math.pi


SEVEN_AXIS_SLOTS: Final = (0, 1, 6, 2, 3, 4, 5)
"""ROS S,L,E,U,R,B,T → controller S,L,U,R,B,T,E: E lives in controller slot 6 (§5.7)."""

# Accelerations and jerks: Yaskawa publishes none (chosen). A cobot gets 2.5 s⁻¹ × its
# joint speed, an industrial arm 4 s⁻¹ × its joint speed; jerk is 10 s⁻¹ × acceleration.
_COBOT_ACCEL_PER_SPEED: Final = 2.5
_INDUSTRIAL_ACCEL_PER_SPEED: Final = 4.0
_JERK_PER_ACCEL: Final = 10.0


def _axis(
    name: str,
    lower_deg: float,
    upper_deg: float,
    speed_deg: float,
    pulses_per_degree: float,
    accel_per_speed: float = _INDUSTRIAL_ACCEL_PER_SPEED,
) -> AxisModel:
    """A rotary axis from the degree figures of the tables in robot-models.md."""
    velocity = _deg(speed_deg)
    accel = round(accel_per_speed * velocity, 2)
    return AxisModel(
        name,
        _deg(lower_deg),
        _deg(upper_deg),
        velocity,
        _ppr(pulses_per_degree),
        accel,
        round(_JERK_PER_ACCEL * accel, 1),
    )


# HC10 (A0) and HC10DT (A1): limits and speeds from robot-models.md §1.2 (manuals HW1483896,
# HW1485083). Pulses/degree chosen (no public value): about the MA1440 S-axis figure users
# measured (1435, robot-models.md §3.3) for the big S/L axes, rounded so that speed × ratio
# is whole pulses per tick (1425, 1250, 925, 910, 650), smaller towards the wrist.
# Accelerations/jerks chosen conservatively for a cobot: about 2.5× the joint speed per
# second, jerk 10× the acceleration per second.
_HC10_AXES: Final = (
    AxisModel("joint_1_s", -math.pi, math.pi, _deg(130), _ppr(1425.0), 5.5, 55.0),
    AxisModel("joint_2_l", -math.pi, math.pi, _deg(130), _ppr(1425.0), 5.5, 55.0),
    AxisModel("joint_3_u", _deg(-5), _deg(355), _deg(180), _ppr(1250.0), 7.5, 75.0),
    AxisModel("joint_4_r", -math.pi, math.pi, _deg(180), _ppr(925.0), 7.5, 75.0),
    AxisModel("joint_5_b", -math.pi, math.pi, _deg(250), _ppr(910.0), 10.5, 105.0),
    AxisModel("joint_6_t", -math.pi, math.pi, _deg(250), _ppr(650.0), 10.5, 105.0),
)


def _dh_6axis(
    d1: float, a1: float, a2: float, a3: float, d4: float, d6: float
) -> tuple[DhLink, ...]:
    """Standard DH of a Motoman 6-axis arm from its URDF origins (derived, not sourced):
    S height d1 and offset a1, upper arm a2, elbow offset a3, forearm d4, flange d6."""
    half = math.pi / 2
    return (
        DhLink(0.0, d1, a1, -half),
        DhLink(-half, 0.0, a2, 0.0),
        DhLink(0.0, 0.0, a3, -half),
        DhLink(0.0, d4, 0.0, half),
        DhLink(0.0, 0.0, 0.0, -half),
        DhLink(0.0, d6, 0.0, 0.0),
    )


def _dh_7axis(base: float, upper: float, fore: float, flange: float) -> tuple[DhLink, ...]:
    """Standard DH of a Motoman 7-axis arm (S-L-E-U-R-B-T, physical order) from its URDF
    origins (derived): S height, L→U and U→B lengths along the arm, B→flange."""
    half = math.pi / 2
    return (
        DhLink(0.0, base, 0.0, -half),
        DhLink(0.0, 0.0, 0.0, half),
        DhLink(0.0, upper, 0.0, -half),
        DhLink(0.0, 0.0, 0.0, half),
        DhLink(0.0, fore, 0.0, -half),
        DhLink(0.0, 0.0, 0.0, half),
        DhLink(0.0, flange, 0.0, 0.0),
    )


def _hc10_dh(flange: float) -> tuple[DhLink, ...]:
    # Standard DH read off the URDF origins of robot-models.md §1.2 (derived):
    # S at 0.275 m, L→U 0.700 m, U→B 0.500 m, B→flange offset 0.162 m, then the flange.
    return (
        DhLink(0.0, 0.275, 0.0, -math.pi / 2),
        DhLink(-math.pi / 2, 0.0, 0.700, 0.0),
        DhLink(0.0, 0.0, 0.0, math.pi / 2),
        DhLink(0.0, 0.500, 0.0, -math.pi / 2),
        DhLink(0.0, 0.162, 0.0, math.pi / 2),
        DhLink(0.0, flange, 0.0, 0.0),
    )


# --- Geometry: joint origins and axes, tool0 and the ``base`` frame (robot-models.md §1) ---

_X: Final = (1.0, 0.0, 0.0)
_Y: Final = (0.0, 1.0, 0.0)
_Z: Final = (0.0, 0.0, 1.0)
_NX: Final = (-1.0, 0.0, 0.0)
_NY: Final = (0.0, -1.0, 0.0)
_NZ: Final = (0.0, 0.0, -1.0)
_HALF_PI: Final = math.pi / 2
# tool0 of the GP-family URDFs: the flange frame turned so that z points out of the flange
# and x up (rpy (π, −π/2, 0), robot-models.md §1.3).
_GP_TOOL0_RPY: Final = (math.pi, -_HALF_PI, 0.0)


@dataclass(frozen=True, slots=True)
class _GroupGeometry:
    joints: tuple[tuple[Vec3, Vec3] | tuple[Vec3, Vec3, Vec3], ...]
    """Per ROS-order joint: (origin xyz, axis) or (origin xyz, axis, origin rpy)."""
    tool0: Transform | None
    base_height: float
    mount: Transform = Transform()


def _group(
    name: str,
    kind: GroupKind,
    axes: tuple[AxisModel, ...],
    dh: tuple[DhLink, ...],
    geometry: _GroupGeometry,
    link_radii: tuple[float, ...] = (),
) -> GroupModel:
    """A control group, home at zero, with each joint's origin and axis, its tool0, base
    height and mount, and its links' capsule radii attached."""
    if len(geometry.joints) != len(axes):
        joints = len(geometry.joints)
        raise ConfigError(f"group {name}: geometry for {joints} of {len(axes)} joints")
    placed = tuple(
        dataclasses.replace(
            axis,
            geometry=JointGeometry(
                Transform(joint[0], joint[2] if len(joint) == 3 else (0.0, 0.0, 0.0)), joint[1]
            ),
        )
        for axis, joint in zip(axes, geometry.joints, strict=True)
    )
    # a 7-axis arm's E sits in controller slot 6; every other group in ROS order
    seven = kind is GroupKind.ROBOT and len(axes) == 7
    slots = SEVEN_AXIS_SLOTS if seven else tuple(range(len(axes)))
    return GroupModel(
        name,
        kind,
        placed,
        slots,
        (0.0,) * len(axes),
        dh,
        mount=geometry.mount,
        tool0=geometry.tool0,
        base_height=geometry.base_height,
        link_radii=link_radii,
    )


def _single_arm(
    name: str,
    description: str,
    axes: tuple[AxisModel, ...],
    dh: tuple[DhLink, ...],
    geometry: _GroupGeometry,
    controllers: frozenset[str],
    *,
    link_radii: tuple[float, ...] = (),
    pfl: bool = False,
) -> RobotModel:
    """A robot of one arm, R1: axes, DH, geometry and collision shapes in one call."""
    group = _group("R1", GroupKind.ROBOT, axes, dh, geometry, link_radii)
    return RobotModel(name, description, (group,), controllers, pfl=pfl)


# HC10 (A0) / HC10DT (A1): robot-models.md §1.2; tool0 on the T axis, rolled by π.
def _hc10_geometry(flange: float) -> _GroupGeometry:
    return _GroupGeometry(
        (
            ((0.0, 0.0, 0.275), _Z),
            ((0.0, 0.0, 0.0), _Y),
            ((0.0, 0.0, 0.700), _NY),
            ((0.0, 0.0, -0.500), _Z),
            ((0.0, 0.162, 0.0), _NY),
            ((0.0, 0.0, 0.0), _Z),
        ),
        Transform((0.0, 0.0, -flange), (math.pi, 0.0, 0.0)),
        0.275,
    )


_Opw = tuple[float, float, float, float, float, float]
"""The OPW lengths of a GP-family arm (robot-models.md §1.3): c1, a1, c2, a2, c3, c4 (m)."""


def _gp_arm(
    name: str,
    description: str,
    axes: tuple[AxisModel, ...],
    opw: _Opw,
    controllers: frozenset[str],
    *,
    link_radii: tuple[float, ...] = (),
) -> RobotModel:
    """A GP-family arm: its DH parameters and its URDF chain both from its OPW lengths,
    so that each length is written once (S height c1 and offset a1, upper arm c2,
    elbow offset a2, forearm c3, flange c4; B and T sit at R)."""
    c1, a1, c2, a2, c3, c4 = opw
    geometry = _GroupGeometry(
        (
            ((0.0, 0.0, c1), _Z),
            ((a1, 0.0, 0.0), _Y),
            ((0.0, 0.0, c2), _NY),
            ((c3, 0.0, a2), _NX),
            ((0.0, 0.0, 0.0), _NY),
            ((0.0, 0.0, 0.0), _NX),
        ),
        Transform((c4, 0.0, 0.0), _GP_TOOL0_RPY),
        c1,
    )
    dh = _dh_6axis(c1, a1, c2, a2, c3, c4)
    return _single_arm(name, description, axes, dh, geometry, controllers, link_radii=link_radii)


# MH5: the ROS2 origins (robot-models.md §1.4: S z 0.330, L x 0.088, U z 0.310, R z 0.040,
# B x 0.305, T x 0.080) with the Motoman axis pattern of §1.1. Neither package gives the MH5
# a tool0 (ROS1 ends at link_t): chosen as the GP family's, on the T axis.
_MH5_GEOMETRY: Final = _GroupGeometry(
    (
        ((0.0, 0.0, 0.330), _Z),
        ((0.088, 0.0, 0.0), _Y),
        ((0.0, 0.0, 0.310), _NY),
        ((0.0, 0.0, 0.040), _NX),
        ((0.305, 0.0, 0.0), _NY),
        ((0.080, 0.0, 0.0), _NX),
    ),
    Transform((0.0, 0.0, 0.0), _GP_TOOL0_RPY),
    0.330,
)

# SIA20D: robot-models.md §1.5; tool0 = link_t turned −π about z; base at 0.41 m.
_SIA20D_GEOMETRY: Final = _GroupGeometry(
    (
        ((0.0, 0.0, 0.41), _Z),
        ((0.0, 0.0, 0.0), _Y),
        ((0.0, 0.0, 0.49), _Z),
        ((0.0, 0.0, 0.0), _NY),
        ((0.0, 0.0, 0.420), _NZ),
        ((0.0, 0.0, 0.0), _NY),
        ((0.0, 0.0, 0.18), _NZ),
    ),
    Transform((0.0, 0.0, 0.0), (0.0, 0.0, -math.pi)),
    0.41,
)

# SDA10F torso: torso_link_b1 1.2 m above base_link (robot-models.md §1.6).
_SDA10F_TORSO_HEIGHT: Final = 1.2


def _sda10f_arm_geometry(reflect: float) -> _GroupGeometry:
    """One SDA10F arm (robot-models.md §1.6; reflect +1 left, −1 right). Its chain hangs off
    the torso, taken at its zero: the arm groups' kinematics do not follow the B1 axis."""
    neg = (0.0, 0.0, -reflect)
    pos = (0.0, 0.0, reflect)
    first_rpy = (_HALF_PI, 0.0, 0.0) if reflect > 0 else (_HALF_PI, 0.0, -math.pi)
    up = (_HALF_PI, 0.0, 0.0)
    down = (-_HALF_PI, 0.0, 0.0)
    return _GroupGeometry(
        (
            ((0.100, 0.265 * reflect, 0.0), neg, first_rpy),
            ((0.0, 0.0, 0.0), neg, down),
            ((0.0, 0.360, 0.0), neg, up),
            ((0.0, 0.0, 0.0), pos, down),
            ((0.0, 0.360, 0.0), pos, up),
            ((0.0, 0.0, 0.0), pos, down),
            ((0.0, 0.155, 0.0), neg, down),
        ),
        Transform((0.0, 0.0, 0.0), (0.0, 0.0, math.pi)),
        # robot-models.md names no `base` frame for the SDA10F: base = base_link (chosen).
        0.0,
        Transform((0.0, 0.0, _SDA10F_TORSO_HEIGHT)),
    )


_SDA10F_TORSO_GEOMETRY: Final = _GroupGeometry((((0.0, 0.0, _SDA10F_TORSO_HEIGHT), _Z),), None, 0.0)


# HC10 / HC10DT link radii (manuals HW1483896, HW1485083): base Ø ~200 mm, S and L
# housings Ø ~190 mm, upper arm Ø ~150 mm, forearm Ø ~130 mm, wrist Ø ~110 mm, flange
# Ø ~90 mm. Link radii of every model: OUR numbers, read off the outline drawings of the
# datasheets and manuals named per robot (the body around each axis, rounded up to the
# next 5 mm so that a capsule encloses its link): good enough to stop the twin at an
# obstacle a few millimetres before the real arm would touch it, not a CAD model.
_HC10_LINK_RADII: Final = (0.100, 0.095, 0.075, 0.065, 0.060, 0.055, 0.045)

HC10: Final = _single_arm(
    "hc10",
    "Yaskawa HC10 (A0) collaborative robot, 10 kg, 6 axes",
    _HC10_AXES,
    _hc10_dh(0.130),
    _hc10_geometry(0.130),
    # Sourced: HC10 on YRC1000 (motoros2#293) and YRC1000micro (motoman#284), §2.
    frozenset({"yrc1000", "yrc1000micro"}),
    link_radii=_HC10_LINK_RADII,
    pfl=True,  # collaborative: Power and Force Limiting
)

# HC10DT (A1): the same kinematics, limits, speeds and body as the HC10 (robot-models.md
# §1.2); only the flange is longer (tool0 at 0.170 m instead of 0.130 m).
HC10DT: Final = _single_arm(
    "hc10dt",
    "Yaskawa HC10DT (A1) collaborative robot, dust/drip-proof, 10 kg, 6 axes",
    _HC10_AXES,
    _hc10_dh(0.170),
    _hc10_geometry(0.170),
    # Sourced for the HC10 family: YRC1000 and YRC1000micro (§2).
    frozenset({"yrc1000", "yrc1000micro"}),
    link_radii=_HC10_LINK_RADII,
    pfl=True,  # collaborative: Power and Force Limiting
)

# GP7 / GP8 / GP12: limits and speeds from robot-models.md §1.3 (datasheets; manuals
# HW1486547, HW1484060; GP8 L 385°/s from the manual, the ROS1 URDF's 6.7495 rad/s is
# 386.7°/s). Pulses/degree chosen: whole pulses per tick at the datasheet speed.
# GP7 / GP8 link radii (manual HW1486547): base ~240 mm wide, S head ~200 mm, L arm
# ~140 mm, U housing ~140 mm, wrist ~100 mm, B ~90 mm, flange Ø 70 mm (ISO 9409-1-31.5).
_GP7_LINK_RADII: Final = (0.120, 0.100, 0.070, 0.070, 0.050, 0.045, 0.035)

GP7: Final = _gp_arm(
    "gp7",
    "Yaskawa GP7 industrial robot, 7 kg, 6 axes",
    (
        _axis("joint_1_s", -170, 170, 375, 1400),
        _axis("joint_2_l", -65, 145, 315, 1400),
        _axis("joint_3_u", -70, 190, 410, 1200),
        _axis("joint_4_r", -190, 190, 550, 800),
        _axis("joint_5_b", -135, 135, 550, 800),
        _axis("joint_6_t", -360, 360, 1000, 480),
    ),
    # OPW geometry of robot-models.md §1.3: c1 0.330, a1 0.040, c2 0.445, a2 0.040,
    # c3 0.440, c4 0.080.
    (0.330, 0.040, 0.445, 0.040, 0.440, 0.080),
    # Not in the stored sources: the GP7 is sold with the YRC1000micro (and YRC1000).
    frozenset({"yrc1000micro", "yrc1000"}),
    link_radii=_GP7_LINK_RADII,
)

GP8: Final = _gp_arm(
    "gp8",
    "Yaskawa GP8 industrial robot, 8 kg, 6 axes",
    (
        _axis("joint_1_s", -170, 170, 455, 1150),
        _axis("joint_2_l", -65, 145, 385, 1150),
        _axis("joint_3_u", -70, 190, 520, 1000),
        _axis("joint_4_r", -190, 190, 550, 800),
        _axis("joint_5_b", -135, 135, 550, 800),
        _axis("joint_6_t", -360, 360, 1000, 480),
    ),
    (0.330, 0.040, 0.345, 0.040, 0.340, 0.080),
    # Not in the stored sources: the GP8 is sold with the YRC1000micro (and YRC1000).
    frozenset({"yrc1000micro", "yrc1000"}),
    link_radii=_GP7_LINK_RADII,  # the GP7's body (same manual)
)

GP12: Final = _gp_arm(
    "gp12",
    "Yaskawa GP12 industrial robot, 12 kg, 6 axes",
    (
        _axis("joint_1_s", -170, 170, 260, 1600),
        _axis("joint_2_l", -90, 155, 230, 1700),
        _axis("joint_3_u", -85, 150, 260, 1450),
        _axis("joint_4_r", -200, 200, 470, 975),
        _axis("joint_5_b", -150, 150, 470, 975),
        _axis("joint_6_t", -455, 455, 700, 650),
    ),
    (0.450, 0.155, 0.614, 0.200, 0.640, 0.100),
    # Not in the stored sources: the GP12 is a YRC1000 robot.
    frozenset({"yrc1000"}),
    # Link radii (manual HW1484060): base ~320 mm, S head ~260 mm, L arm ~180 mm, U ~170 mm,
    # wrist ~130 mm, B ~110 mm, flange Ø 90 mm.
    link_radii=(0.160, 0.130, 0.090, 0.085, 0.065, 0.055, 0.045),
)

# MH5: joint names of the ROS1 package (older joint_s naming); limits and speeds of the
# ROS2 package, which rebuilt them from the Yaskawa manuals (robot-models.md §1.4). The
# ROS1 URDF's 2.96–6.97 rad/s come from an old datasheet and are half the manual's.
MH5: Final = _single_arm(
    "mh5",
    "Yaskawa MH5 industrial robot, 5 kg, 6 axes",
    (
        _axis("joint_s", -170, 170, 376, 1250),
        _axis("joint_l", -65, 150, 350, 1250),
        _axis("joint_u", -70, 190, 400, 1100),
        _axis("joint_r", -190, 190, 450, 700),
        _axis("joint_b", -135, 135, 450, 700),
        _axis("joint_t", -360, 360, 720, 475),
    ),
    # ROS2 origins: S z 0.330, L x 0.088, U z 0.310, R z 0.040, B x 0.305, T x 0.080.
    _dh_6axis(0.330, 0.088, 0.310, 0.040, 0.305, 0.080),
    _MH5_GEOMETRY,
    # Partly sourced: the ROS1 package's U limits were measured on an MH5F, the FS100
    # variant (§1.4); DX100 and DX200 are the MH5's controllers of its time (not sourced).
    frozenset({"dx100", "dx200", "fs100"}),
    # Link radii (datasheet MH5/MH5L): about the GP7's body, slightly slimmer wrist.
    link_radii=(0.115, 0.095, 0.065, 0.065, 0.050, 0.040, 0.030),
)

# SIA20D: 7 axes, ROS order S-L-E-U-R-B-T, limits and speeds from robot-models.md §1.5
# (manual HW0485536). Pulses/degree chosen.
SIA20D: Final = _single_arm(
    "sia20d",
    "Yaskawa SIA20D 7-axis robot, 20 kg",
    (
        _axis("joint_s", -180, 180, 130, 1525),
        _axis("joint_l", -110, 110, 130, 1525),
        _axis("joint_e", -170, 170, 170, 1225),
        _axis("joint_u", -130, 130, 170, 1225),
        _axis("joint_r", -180, 180, 200, 900),
        _axis("joint_b", -110, 110, 200, 900),
        _axis("joint_t", -180, 180, 400, 600),
    ),
    _dh_7axis(0.41, 0.49, 0.42, 0.18),
    _SIA20D_GEOMETRY,
    # Not in the stored sources: the "D" suffix is the DX100 generation (SIA20F: FS100).
    frozenset({"dx100"}),
    # Link radii (manual HW0485536): base ~300 mm, S/L ~240 mm, E/U ~200 mm, R/B ~150 mm,
    # flange Ø 80 mm.
    link_radii=(0.150, 0.120, 0.120, 0.100, 0.100, 0.075, 0.075, 0.040),
)


def _sda10f_arm(side: str) -> tuple[AxisModel, ...]:
    # robot-models.md §1.6 (manual HW0485584): the same limits and speeds for both arms.
    p = f"arm_{side}_"
    return (
        _axis(p + "joint_1_s", -180, 180, 170, 1225),
        _axis(p + "joint_2_l", -110, 110, 170, 1225),
        _axis(p + "joint_3_e", -170, 170, 170, 1225),
        _axis(p + "joint_4_u", -135, 135, 170, 1225),
        _axis(p + "joint_5_r", -180, 180, 200, 900),
        _axis(p + "joint_6_b", -110, 110, 200, 900),
        _axis(p + "joint_7_t", -180, 180, 400, 600),
    )


# SDA10F arm link radii (manual HW0485584): the torso column Ø ~300 mm is each arm's base
# link; shoulder ~180 mm, upper arm ~150 mm, forearm ~130 mm, wrist ~110 mm, flange Ø 70 mm.
_SDA10F_ARM_LINK_RADII: Final = (0.150, 0.090, 0.090, 0.075, 0.075, 0.065, 0.055, 0.035)


def _torso(name: str) -> GroupModel:
    # torso_joint_b1 and _b2 are one physical axis (URDF mimic), ±170°, 130°/s (§1.6).
    # DH (derived): the torso base sits 1.2 m above base_link. No link radii: the arms'
    # base links cover the torso column.
    axis = _axis(name, -170, 170, 130, 1525)
    group = "B1" if name.endswith("b1") else "B2"
    dh = (DhLink(0.0, 1.2, 0.0, 0.0),)
    return _group(group, GroupKind.BASE, (axis,), dh, _SDA10F_TORSO_GEOMETRY)


# SDA10F: dual arm + torso in four groups, R1 left arm, R2 right arm, B1/B2 the torso
# (robot-models.md §1.6; Yaskawa says B1 and B2 must get the same data, motoman#343).
SDA10F: Final = RobotModel(
    name="sda10f",
    description="Yaskawa SDA10F dual-arm robot: two 7-axis arms (R1, R2) and a torso (B1, B2)",
    groups=(
        _group(
            "R1",
            GroupKind.ROBOT,
            _sda10f_arm("left"),
            _dh_7axis(0.0, 0.36, 0.36, 0.155),
            _sda10f_arm_geometry(1.0),
            _SDA10F_ARM_LINK_RADII,
        ),
        _group(
            "R2",
            GroupKind.ROBOT,
            _sda10f_arm("right"),
            _dh_7axis(0.0, 0.36, 0.36, 0.155),
            _sda10f_arm_geometry(-1.0),
            _SDA10F_ARM_LINK_RADII,
        ),
        _torso("torso_joint_b1"),
        _torso("torso_joint_b2"),
    ),
    # Sourced: model YR-SDA010F-A00 is an FS100 robot (§1.6). MotoROS's SDA job folder also
    # covers DX200 and YRC1000 SDA cells, but not necessarily this model.
    controllers=frozenset({"fs100"}),
)

ROBOTS: Final[dict[str, RobotModel]] = {
    r.name: r for r in (HC10, HC10DT, GP7, GP8, GP12, MH5, SIA20D, SDA10F)
}
"""Every built-in robot, by lower-case name."""

DEFAULT_ROBOT: Final = "hc10"


def robot_model(name: str) -> RobotModel:
    """Look a robot up by name (case-insensitive); a clear error lists the known ones."""
    try:
        return ROBOTS[name.lower()]
    except KeyError:
        known = ", ".join(sorted(ROBOTS))
        raise ConfigError(f"unknown robot {name!r}; known robots: {known}") from None
