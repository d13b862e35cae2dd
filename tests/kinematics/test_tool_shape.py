"""A tool's ``shape`` on the flange (kinematics/collision.py ``GroupBody.set_tool``):
every kind of shape touches what it reaches, and the bounds the twin and ``check`` use
to skip probes (reach, lever arms) still enclose it."""

from __future__ import annotations

import numpy as np
import pytest

from pymotoros.kinematics.collision import TOOL_LINK, CollisionWorld, world_for_cell
from pymotoros.models.cell import cell_models_from_dict
from pymotoros.models.cell_tools import CellTool
from pymotoros.models.robots import Transform
from pymotoros.models.workspace import parse_tool_shape

POSE = [0.0, -1.0, 1.0, 0.0, -2.0, 0.0]
"""The HC10's flange pointing down at (-0.13, 0.16, 0.73) in base_link."""
FLANGE_Z = 0.731


def _world(top_below_flange: float) -> CollisionWorld:
    cell = cell_models_from_dict(
        {
            "robot": {"model": "hc10"},
            "workspace": {
                "obstacles": [
                    {
                        "name": "plate",
                        "box": [0.1, 0.1, 0.02],
                        "xyz": [-0.13, 0.16, FLANGE_Z - top_below_flange - 0.01],
                    }
                ]
            },
        }
    )
    return world_for_cell(cell)


@pytest.mark.parametrize(
    ("shape", "reaches_m"),
    [
        ({"capsule": [0.02, 0.2]}, 0.22),
        ({"box": [0.05, 0.05, 0.2]}, 0.2),
        ({"cylinder": [0.03, 0.2]}, 0.2),
        ({"sphere": 0.1}, 0.2),
        ({"box": [0.05, 0.05, 0.05], "xyz": [0.0, 0.0, 0.175]}, 0.2),
    ],
)
def test_each_shape_touches_what_it_reaches_and_no_farther(
    shape: dict[str, object], reaches_m: float
) -> None:
    tool = CellTool(1, "t", Transform(), parse_tool_shape(shape, "shape"))
    near = _world(reaches_m - 0.03)
    near.set_tool(0, tool)
    hits = near.contacts([POSE])
    assert [(c.obstacle, c.link) for c in hits] == [("plate", TOOL_LINK)]
    far = _world(reaches_m + 0.03)
    far.set_tool(0, tool)
    clearance, hits = far.probe([POSE])
    assert hits == []
    assert 0.0 < clearance <= 0.031


def test_the_reach_and_lever_bounds_enclose_a_box_tool() -> None:
    world = _world(0.5)
    bare = max(world.joint_reach(0))
    tool = CellTool(1, "t", Transform(), parse_tool_shape({"box": [0.1, 0.1, 0.4]}, "shape"))
    world.set_tool(0, tool)
    assert max(world.joint_reach(0)) >= bare + 0.4
    body = world.bodies[0]
    assert body is not None
    body.place(np.asarray(POSE))
    levers = world.lever_arms(0)
    # the box's far corner from axis T: its bounding sphere (half-diagonal) is counted
    assert levers[5] >= float(np.hypot(0.05, 0.05))


def test_a_tool_without_shape_is_a_capsule_to_its_tcp() -> None:
    world = _world(0.17)
    world.set_tool(0, Transform((0.0, 0.0, 0.2)))
    assert [c.link for c in world.contacts([POSE])] == [TOOL_LINK]
    world.set_tool(0, CellTool(2))  # TCP on tool0: no tool shape at all
    assert world.contacts([POSE]) == []
