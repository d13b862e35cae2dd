"""A URDF of a robot model: the chain base_link → tool0 with simple shapes, no meshes.

Written for viewers and planners (RViz, MoveIt, the web pendant) that need the geometry
of the simulated robot without the ROS support packages. Each link gets a cylinder from
its joint to the next joint, so the robot is visible without meshes. Every group of the
model is written: arm groups hang off ``base_link`` (SDA10F arms off the torso's mount
point), each with its own ``tool0`` (prefixed by the group when there are several).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Final

from pymotoros.errors import KinematicsError
from pymotoros.kinematics.chain import joint_geometry
from pymotoros.models.robots import RobotModel, Transform

LINK_RADIUS_M: Final = 0.04
"""Radius of the cylinders drawn for the links (chosen: a visible, slim arm)."""
MIN_LINK_LENGTH_M: Final = 1e-6
"""Links shorter than this get no cylinder (joints that share an origin)."""
_EFFORT_PLACEHOLDER: Final = 100.0
"""URDF requires an effort limit; robot-models.md gives placeholders (100) for several
models, so every joint gets that value here: no planner of ours uses it."""


def _num(value: float) -> str:
    """Shortest text that reads back as the same float (no rounding of π and friends)."""
    text = repr(float(value) + 0.0)
    return text[:-2] if text.endswith(".0") else text


def _fmt(values: tuple[float, ...]) -> str:
    return " ".join(_num(v) for v in values)


def _origin(parent: ET.Element, frame: Transform) -> None:
    ET.SubElement(parent, "origin", xyz=_fmt(frame.xyz), rpy=_fmt(frame.rpy))


def _link(root: ET.Element, name: str, child_offset: tuple[float, float, float] | None) -> None:
    link = ET.SubElement(root, "link", name=name)
    if child_offset is None:
        return
    length = math.sqrt(sum(c * c for c in child_offset))
    if length < MIN_LINK_LENGTH_M:
        return
    # A cylinder along z, turned to point from this joint to the next one.
    x, y, z = (c / length for c in child_offset)
    pitch = math.acos(max(-1.0, min(1.0, z)))
    yaw = math.atan2(y, x)
    mid = tuple(c / 2 for c in child_offset)
    visual = ET.SubElement(link, "visual")
    ET.SubElement(visual, "origin", xyz=_fmt(mid), rpy=_fmt((0.0, pitch, yaw)))
    geometry = ET.SubElement(visual, "geometry")
    ET.SubElement(geometry, "cylinder", radius=f"{LINK_RADIUS_M:g}", length=_num(length))


def urdf_for(robot: RobotModel) -> str:
    """The URDF text of ``robot``: every group's chain from ``base_link`` to its ``tool0``."""
    root = ET.Element("robot", name=robot.name)
    ET.SubElement(root, "link", name="base_link")
    several = len(robot.groups) > 1
    base_written = False
    for group in robot.groups:
        if any(a.geometry is None for a in group.axes):
            raise KinematicsError(f"{robot.name} {group.name}: no joint geometry for a URDF")
        prefix = f"{group.name.lower()}_" if several else ""
        if not base_written and group.base_height:
            _link(root, "base", None)
            joint = ET.SubElement(root, "joint", name="base_link-base", type="fixed")
            _origin(joint, Transform((0.0, 0.0, group.base_height)))
            ET.SubElement(joint, "parent", link="base_link")
            ET.SubElement(joint, "child", link="base")
            base_written = True
        parent = "base_link"
        if group.mount != Transform():
            mount = f"{prefix}mount"
            _link(root, mount, None)
            joint = ET.SubElement(root, "joint", name=f"{prefix}base_link-mount", type="fixed")
            _origin(joint, group.mount)
            ET.SubElement(joint, "parent", link="base_link")
            ET.SubElement(joint, "child", link=mount)
            parent = mount
        axes = group.axes
        for i, axis in enumerate(axes):
            geo = joint_geometry(axis)
            child = f"{prefix}link_{i + 1}_{axis.name.rsplit('_', 1)[-1]}"
            nxt = axes[i + 1].geometry if i + 1 < len(axes) else None
            offset = nxt.origin.xyz if nxt is not None else None
            if nxt is None and group.tool0 is not None:
                offset = group.tool0.xyz
            _link(root, child, offset)
            joint = ET.SubElement(
                root, "joint", name=axis.name, type="prismatic" if axis.linear else "revolute"
            )
            _origin(joint, geo.origin)
            ET.SubElement(joint, "parent", link=parent)
            ET.SubElement(joint, "child", link=child)
            ET.SubElement(joint, "axis", xyz=_fmt(geo.axis))
            ET.SubElement(
                joint,
                "limit",
                lower=_num(axis.lower),
                upper=_num(axis.upper),
                velocity=_num(axis.max_velocity),
                effort=f"{_EFFORT_PLACEHOLDER:g}",
            )
            parent = child
        flange = f"{prefix}flange"
        _link(root, flange, None)
        joint = ET.SubElement(root, "joint", name=f"{prefix}link_t-flange", type="fixed")
        _origin(joint, Transform())
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=flange)
        tool0 = f"{prefix}tool0"
        _link(root, tool0, None)
        joint = ET.SubElement(root, "joint", name=f"{prefix}link_t-tool0", type="fixed")
        _origin(joint, group.tool0 or Transform())
        ET.SubElement(joint, "parent", link=parent)
        ET.SubElement(joint, "child", link=tool0)
    ET.indent(root)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
