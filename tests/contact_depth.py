"""Where a robot driven into an obstacle stands, for the contact tests (in-memory twin
and TCP): its commanded joints and how deep it is in the obstacle."""

from __future__ import annotations

from operator import mul

from pymotoros.controller import VirtualController
from pymotoros.controller.cell import CellConfig
from pymotoros.kinematics.collision import CollisionWorld
from pymotoros.motion import GroupAxes, from_pulses


def group_axes(controller: VirtualController) -> GroupAxes:
    """The first group's axes of ``controller``'s cell."""
    return GroupAxes.from_model(controller.cell.groups[0], controller.cell.controller)


def commanded_joints(controller: VirtualController) -> list[float]:
    """The first group's commanded joint values (rad), from its commanded pulses."""
    axes = group_axes(controller)
    return list(from_pulses(controller.commanded_pulses(0), axes)[: axes.num_axes])


def depth_and_one_tick(cell: CellConfig, controller: VirtualController) -> tuple[float, float]:
    """How deep the commanded robot is in the obstacles of ``cell``, and the farthest one
    tick at full speed can carry any point of it (each joint's largest increment × its
    reach)."""
    world = CollisionWorld(cell.groups, cell.workspace)
    _, contacts = world.probe([commanded_joints(controller)])
    depth = max((-c.distance_m for c in contacts), default=0.0)
    axes = group_axes(controller)
    reach = world.joint_reach(0)
    per_slot = [0.0] * 8
    for k in range(axes.num_axes):
        slot = axes.ros_to_slot[k]
        per_slot[slot] = reach[k] / axes.pulses_per_unit[slot]
    return depth, sum(map(mul, axes.max_increment, per_slot))
