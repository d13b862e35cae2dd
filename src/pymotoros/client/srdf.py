"""Named joint poses: a built-in ``home`` per robot model, and the ``group_state`` entries of
an SRDF file (the MoveIt configuration format)::

    <group_state name="stretched" group="manipulator">
        <joint name="joint_1_s" value="0"/>
        ...
    </group_state>

Parsed with the standard library; poses keep the order of the file, so that "visit
every named pose in order" does what the file says.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from pymotoros.client.errors import ClientError
from pymotoros.models import GroupModel

HOME: Final = "home"
"""Name of the built-in pose (``GroupModel.home``); an SRDF entry of that name wins."""


class NamedPoseError(ClientError, ValueError):
    """An SRDF file cannot be read, or a named pose is unknown or does not fit the robot."""


@dataclass(frozen=True, slots=True)
class NamedPose:
    """A named set of joint values for one planning group."""

    name: str
    group: str
    joints: Mapping[str, float]
    """Joint name → value (rad, m), in the order of the file."""

    def positions_for(self, group: GroupModel) -> tuple[float, ...]:
        """The values in the model group's joint order; every joint must be named."""
        missing = [n for n in group.joint_names if n not in self.joints]
        if missing:
            raise NamedPoseError(
                f"pose {self.name!r} does not set {', '.join(missing)} "
                f"(it sets {', '.join(self.joints)})"
            )
        return tuple(self.joints[n] for n in group.joint_names)


def parse_srdf(source: str | Path) -> tuple[NamedPose, ...]:
    """Every ``group_state`` of an SRDF file (a path) or text (a string holding ``<``)."""
    try:
        if isinstance(source, Path) or "<" not in source:
            root = ET.parse(source).getroot()  # noqa: S314 - a local file the user chose
        else:
            root = ET.fromstring(source)  # noqa: S314
    except (OSError, ET.ParseError) as exc:
        raise NamedPoseError(f"cannot read SRDF {source!s:.80}: {exc}") from exc
    poses = []
    for state in root.iter("group_state"):
        name = state.get("name")
        group = state.get("group", "")
        if not name:
            raise NamedPoseError("a group_state in the SRDF has no name")
        joints: dict[str, float] = {}
        for joint in state.iter("joint"):
            jname, value = joint.get("name"), joint.get("value")
            if not jname or value is None:
                raise NamedPoseError(f"group_state {name!r}: a joint lacks a name or a value")
            try:
                joints[jname] = float(value.split()[0])
            except (ValueError, IndexError):
                raise NamedPoseError(
                    f"group_state {name!r}: joint {jname} has value {value!r}, not a number"
                ) from None
        poses.append(NamedPose(name, group, joints))
    return tuple(poses)


def builtin_home(group: GroupModel) -> NamedPose:
    """The model's ``home`` pose."""
    return NamedPose(HOME, group.name, dict(zip(group.joint_names, group.home, strict=True)))


def find_pose(
    name: str, group: GroupModel, poses: Sequence[NamedPose] = (), *, planning_group: str = ""
) -> NamedPose:
    """Look ``name`` up in ``poses`` (optionally only those of ``planning_group``), then
    fall back on the built-in ``home``; the error lists what exists."""
    for pose in poses:
        if pose.name == name and (not planning_group or pose.group == planning_group):
            return pose
    if name == HOME:
        return builtin_home(group)
    known = sorted({p.name for p in poses} | {HOME})
    raise NamedPoseError(f"no named pose {name!r}; known: {', '.join(known)}")
