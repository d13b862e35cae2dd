"""Collision shapes of the robot models as data: one capsule radius per link.

Each link of a robot group is a capsule around the segment from its joint to the next
joint (the last link: to ``tool0``; the base link: from ``base_link`` to the first
joint), so the segments come from the joint origins of :mod:`pymotoros.models.robots`
and only the radii are new data. They are OUR numbers, read off the outline drawings
of Yaskawa's datasheets and manuals named per robot below (the body around each axis,
rounded up to the next 5 mm so that a capsule encloses its link): good enough to stop
the twin at an obstacle a few millimetres before the real arm would touch it, not a
CAD model. The tool is a capsule from ``tool0`` to the active tool's TCP (radius
``workspace.tool_radius_m``), see :mod:`pymotoros.kinematics.collision`.

Only robot groups (R1, R2 …) get shapes; a base or station axis (the SDA10F torso
B1/B2) has none: the arms' base links cover the torso column.
"""

from __future__ import annotations

from typing import Final

from pymotoros.models.robots import GroupKind, GroupModel

LINK_RADII_M: Final[dict[str, tuple[float, ...]]] = {
    # HC10 / HC10DT (manuals HW1483896, HW1485083): base Ø ~200 mm, S and L housings
    # Ø ~190 mm, upper arm Ø ~150 mm, forearm Ø ~130 mm, wrist Ø ~110 mm, flange Ø ~90 mm.
    "hc10": (0.100, 0.095, 0.075, 0.065, 0.060, 0.055, 0.045),
    "hc10dt": (0.100, 0.095, 0.075, 0.065, 0.060, 0.055, 0.045),
    # GP7 / GP8 (manual HW1486547): base ~240 mm wide, S head ~200 mm, L arm ~140 mm,
    # U housing ~140 mm, wrist ~100 mm, B ~90 mm, flange Ø 70 mm (ISO 9409-1-31.5).
    "gp7": (0.120, 0.100, 0.070, 0.070, 0.050, 0.045, 0.035),
    "gp8": (0.120, 0.100, 0.070, 0.070, 0.050, 0.045, 0.035),
    # GP12 (manual HW1484060): base ~320 mm, S head ~260 mm, L arm ~180 mm, U ~170 mm,
    # wrist ~130 mm, B ~110 mm, flange Ø 90 mm.
    "gp12": (0.160, 0.130, 0.090, 0.085, 0.065, 0.055, 0.045),
    # MH5 (datasheet MH5/MH5L): about the GP7's body, slightly slimmer wrist.
    "mh5": (0.115, 0.095, 0.065, 0.065, 0.050, 0.040, 0.030),
    # SIA20D (manual HW0485536): base ~300 mm, S/L ~240 mm, E/U ~200 mm, R/B ~150 mm,
    # flange Ø 80 mm.
    "sia20d": (0.150, 0.120, 0.120, 0.100, 0.100, 0.075, 0.075, 0.040),
    # SDA10F arms (manual HW0485584): the torso column Ø ~300 mm is each arm's base link;
    # shoulder ~180 mm, upper arm ~150 mm, forearm ~130 mm, wrist ~110 mm, flange Ø 70 mm.
    "sda10f": (0.150, 0.090, 0.090, 0.075, 0.075, 0.065, 0.055, 0.035),
}
"""Per robot model: the base link's radius, then one per joint's link (ROS order), m."""


def link_radii(robot: str, group: GroupModel) -> tuple[float, ...] | None:
    """The capsule radii of a group's links (base link first), None for a group with
    no collision shapes (a base or station axis, or a model without data)."""
    if group.kind is not GroupKind.ROBOT:
        return None
    radii = LINK_RADII_M.get(robot.lower())
    if radii is None or len(radii) != group.num_axes + 1:
        return None
    return radii


def link_name(joint_name: str) -> str:
    """The ROS-Industrial link after a joint: ``joint_1_s`` → ``link_1_s``,
    ``arm_left_joint_2_l`` → ``arm_left_link_2_l``."""
    return joint_name.replace("joint", "link", 1) if "joint" in joint_name else f"{joint_name}_link"


__all__ = ["LINK_RADII_M", "link_name", "link_radii"]
