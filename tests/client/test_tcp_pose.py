"""``robot.tcp_pose()``: the TCP from the joint feedback, with the client's tool table."""

from __future__ import annotations

import pytest

from pymotoros.controller.cell import cell_from_dict
from pymotoros.errors import PymotorosError
from pymotoros.testing import twin

TCP = (0.0, 0.0, 0.2)


async def test_tcp_pose_matches_the_twin_with_the_same_tool() -> None:
    cell = cell_from_dict(
        {"groups": [{"robot": "hc10", "tools": [{"number": 3, "tcp_m": list(TCP)}]}]}
    )
    async with twin(cell=cell) as (client, tw):
        await client.enable()
        await client.move_joints((0.3, 0.4, 1.9, 0.2, 0.5, 0.1))
        # Tool 0 after boot: the TCP is tool0.
        snap = tw.controller.snapshot().groups[0].tcp
        assert snap is not None
        assert client.tcp_pose() == pytest.approx(snap.feedback, abs=1e-5)
        client.tools.define(3, TCP)
        await client.select_tool(3)
        snap = tw.controller.snapshot().groups[0].tcp
        assert snap is not None
        assert client.tcp_pose() == pytest.approx(snap.feedback, abs=1e-5)
        tool0 = client.tcp_pose(frame="tool0")
        assert client.tcp_pose() != pytest.approx(tool0, abs=1e-3)
        base_link = client.tcp_pose(reference="base_link")
        assert base_link[2] - client.tcp_pose()[2] == pytest.approx(0.275)


def test_tool_numbers_are_checked() -> None:
    from pymotoros.client.tools import ToolTable
    from pymotoros.models import robot_model

    table = ToolTable(robot_model("hc10"))
    with pytest.raises(ValueError, match=r"0\.\.63"):
        table.define(64, TCP)
    with pytest.raises(PymotorosError, match="6 joints, got 5"):
        table.chain(0).pose([0.0] * 5)


def test_the_blocking_client_has_the_cartesian_calls() -> None:
    from pymotoros.testing import sync_twin

    with sync_twin(robot="hc10") as (robot, _):
        robot.enable()
        robot.move_joints((0.0, 0.5, 1.9, 0.0, 0.9, 0.0))
        before = robot.tcp_pose()
        robot.move_relative(dz=-0.02)
        assert robot.tcp_pose()[2] == pytest.approx(before[2] - 0.02, abs=1e-4)
        regs = robot.read_register_outputs({"336": 1})
        assert regs.axis_positions() == (None,) * 8  # no register given: nothing output
