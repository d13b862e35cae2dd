"""The pendant's document carries the tool in force, placed as the twin's contact check
mounts it, and the frames of the poses and obstacles (issue 29 item 5)."""

from __future__ import annotations

import numpy as np
import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.kinematics import chain_for
from pymotoros.kinematics.collision import TOOL_LINK, CollisionWorld
from pymotoros.models.robots import Transform
from pymotoros.runtime.http_api import create_http_app
from pymotoros.runtime.pendant.workspace_view import WorkspaceView

from .support import STATS

Q = (0.2, 0.4, 1.5, 0.1, -0.6, 0.3)
BOX_TOOL = {
    "robot": {"model": "hc10"},
    "tools": [
        {
            "number": 1,
            "name": "spindle",
            "tcp_m": [0.0, 0.0, 0.2],
            "shape": {"box": [0.1, 0.06, 0.2]},
        },
        {"number": 2, "name": "gripper", "tcp_m": [0.0, 0.0, 0.15]},
    ],
    "workspace": {"tool_radius_m": 0.04},
    "initial": {"joints": {"R1": list(Q)}, "tool": {"R1": 1}},
}


def _tool0_and_tcp(tcp: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    chain = chain_for("hc10", Transform(tcp))
    tool0 = np.array(chain.pose(list(Q), "tool0", "base_link")[:3])
    point = np.array(chain.pose(list(Q), "tcp", "base_link")[:3])
    return tool0, point


def test_a_box_tool_is_placed_on_tool0_with_its_tcp() -> None:
    view = WorkspaceView(cell_from_dict(BOX_TOOL))
    placed = view.robot(0, Q, 1)
    assert placed is not None
    capsules, tool = placed
    assert len(capsules) == 7  # the base link and six links: the tool is apart
    assert tool is not None
    assert (tool["number"], tool["name"], tool["shape"]) == (1, "spindle", "box")
    assert tool["size"] == pytest.approx([0.1, 0.06, 0.2])
    tool0, tcp = _tool0_and_tcp((0.0, 0.0, 0.2))
    assert tool["tool0"] == pytest.approx(tool0, abs=1e-4)
    assert tool["tcp"] == pytest.approx(tcp, abs=1e-4)
    # a box standing on the flange along tool0's z: its centre half its length out
    assert tool["xyz"] == pytest.approx((tool0 + tcp) / 2, abs=1e-4)


def test_the_default_tool_shape_is_the_contact_checks_capsule() -> None:
    """No shape: a capsule from tool0 to the TCP of the workspace's tool radius, exactly
    the part the twin's contact check mounts."""
    cell = cell_from_dict(BOX_TOOL)
    placed = WorkspaceView(cell).robot(0, Q, 2)
    assert placed is not None
    tool = placed[1]
    assert tool is not None
    assert (tool["shape"], tool["size"]) == ("capsule", pytest.approx([0.04, 0.15]))
    world = CollisionWorld(cell.groups, cell.workspace)
    world.set_tool(0, cell.tool(0, 2).cell_tool)
    body = world.bodies[0]
    assert body is not None
    body.place(np.array(Q))
    part = body.tool_part
    assert part is not None
    assert part.name == TOOL_LINK
    assert tool["xyz"] == pytest.approx(body.world_of(part).translation, abs=1e-4)
    assert part.radius == pytest.approx(tool["size"][0])


def test_a_tool_at_tool0_has_no_shape_but_a_tcp() -> None:
    placed = WorkspaceView(cell_from_dict(BOX_TOOL)).robot(0, Q, 5)  # an empty tool file
    assert placed is not None
    tool = placed[1]
    assert tool is not None
    assert tool["shape"] is None
    assert tool["tcp"] == tool["tool0"]


def test_pendant_document_has_the_tool_in_force_and_the_frames() -> None:
    controller = VirtualController(cell=cell_from_dict(BOX_TOOL))
    doc = create_http_app(controller, lambda: STATS).state.pendant_feed.document()
    group = doc["groups"][0]
    assert group["tool"] == 1
    assert group["tool_body"]["name"] == "spindle"
    assert group["base_frame"] == {"name": "base", "above_base_link_m": 0.275}
    assert doc["pendant"]["workspace_frame"] == {"name": "base_link", "of": "R1"}
    # the drawn TCP (base_link) is the state's TCP (base) raised by the S-axis height
    base_tcp = group["tcp"]["feedback"]
    drawn = group["tool_body"]["tcp"]
    assert drawn == pytest.approx([base_tcp[0], base_tcp[1], base_tcp[2] + 0.275], abs=1e-4)
