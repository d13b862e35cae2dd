"""``RobotClient`` is a facade over parts; each part works on its own (issue 19)."""

from __future__ import annotations

import inspect

import pytest

from pymotoros.client import ClientError, RobotClient
from pymotoros.client.connection import Ports
from pymotoros.client.geometry import Geometry
from pymotoros.client.io_port import IoPort
from pymotoros.client.link import Link
from pymotoros.client.motion import Motion
from pymotoros.client.motion_commands import MotionCommands
from pymotoros.client.state import StateTracker
from pymotoros.client.state_view import StateView
from pymotoros.client.tools import ToolTable
from pymotoros.models import controller_model, robot_model
from pymotoros.protocol.constants import Port
from pymotoros.testing import TWIN_HOST, Twin

HC10 = robot_model("hc10")
YRC = controller_model("yrc1000")


def _link(tw: Twin) -> Link:
    return Link(
        TWIN_HOST,
        Ports(),
        YRC.byte_order,
        timeout_s=5.0,
        connect_timeout_s=5.0,
        connector=tw.connect,
    )


def test_a_link_that_is_not_open_says_what_to_connect() -> None:
    link = Link("127.0.0.1", Ports(), YRC.byte_order, timeout_s=1.0, connect_timeout_s=1.0)
    with pytest.raises(
        ClientError, match=r"the motion port is not connected \(connect\(motion=True\)\)"
    ):
        link.need(Port.MOTION)
    view = StateView(
        link, StateTracker({0: 6}), HC10, MotionCommands(link, ToolTable(HC10), 1).get_dh_parameters
    )
    assert view.group_index("r1") == 0


async def test_the_motion_commands_and_the_io_port_on_their_own() -> None:
    async with Twin(robot="hc10") as tw:
        link = _link(tw)
        tracker = StateTracker({0: 6})
        await link.open(
            motion=True, state=False, io=False, on_state=tracker.feed, on_state_lost=tracker.lost
        )
        try:
            commands = MotionCommands(link, ToolTable(HC10), 1)
            assert (await commands.check_motion_ready()).ready is False  # not enabled yet
            await commands.select_tool(3)
            assert tw.controller.snapshot().groups[0].tool == 3
            io = IoPort(link, YRC)  # bits go over the motion port when only that one is open
            await io.write_io_bit(10010, 1)
            assert await io.read_io_bit(10010) == 1
            with pytest.raises(ClientError, match="io port is not connected"):
                await io.read_mregister(1)
        finally:
            await link.close()


def test_the_facade_forwards_each_part_with_its_signature() -> None:
    parts = (StateView, MotionCommands, IoPort, Motion, Geometry)
    forwarded = 0
    for name in dir(RobotClient):
        member = inspect.getattr_static(RobotClient, name)
        wrapped = getattr(member, "__wrapped__", None)
        if name.startswith("_") or wrapped is None:
            continue
        forwarded += 1
        assert any(getattr(part, wrapped.__name__, None) is wrapped for part in parts), name
        assert inspect.iscoroutinefunction(member) == inspect.iscoroutinefunction(wrapped), name
        assert inspect.signature(member) == inspect.signature(wrapped), name
        assert member.__doc__ == wrapped.__doc__, name
    assert forwarded >= 40
