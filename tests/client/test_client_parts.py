"""``RobotClient`` is built of parts; each part works on its own (issue 19)."""

from __future__ import annotations

import asyncio
import inspect
from collections.abc import Coroutine
from typing import Any, TypeVar

import pytest

from pymotoros.client import ClientError, RobotClient
from pymotoros.client.blocking import BlockingFacade, after_first_state, blocking_twin
from pymotoros.client.calls import RobotCalls
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
_T = TypeVar("_T")
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


def _without_self(function: object) -> inspect.Signature:
    signature = inspect.signature(function)  # type: ignore[arg-type]
    return signature.replace(parameters=list(signature.parameters.values())[1:])


def test_each_call_has_the_signature_of_the_part_it_calls() -> None:
    """The client's calls are real definitions (``RobotCalls``, issue 30), each with the
    parameters, kind (coroutine or not) and return annotation of the part's method of
    the same name it calls."""
    parts = (StateView, MotionCommands, IoPort, Motion, Geometry)
    client = RobotClient(robot="hc10")
    checked = 0
    for name in dir(RobotCalls):
        homes = [getattr(part, name) for part in parts if hasattr(part, name)]
        if name.startswith("_") or not homes:
            continue
        checked += 1
        (method,) = homes
        call = getattr(client, name)
        assert inspect.iscoroutinefunction(call) == inspect.iscoroutinefunction(method), name
        assert inspect.signature(call) == _without_self(method), name
        assert call.__doc__, name
    assert checked >= 35  # most calls have a part method of the same name (not ping: exchange)


class _ToyCalls:
    @blocking_twin
    async def double(self, x: int) -> int:
        """Twice ``x``, after one event-loop turn."""
        await asyncio.sleep(0)
        return 2 * x

    @after_first_state
    def latest(self) -> str:
        """What the facade waited for first."""
        return "state"


class _ToyClient(_ToyCalls):
    pass


class _ToyFacade(BlockingFacade, _ToyCalls):
    def __init__(self) -> None:
        self.client = _ToyClient()
        self.waited = 0

    def run(self, coro: Coroutine[Any, Any, _T]) -> _T:
        return asyncio.run(coro)

    def wait_for_first_state(self) -> None:
        self.waited += 1


def test_one_definition_is_awaited_on_the_client_and_blocks_on_the_facade() -> None:
    """``client.blocking``: the same method, a coroutine on the client, a blocking call
    with the same signature on the facade (on its class too, taking the facade first)."""
    facade = _ToyFacade()
    assert asyncio.run(_ToyClient().double(3)) == 6
    assert facade.double(4) == 8
    assert _ToyFacade.double(facade, 5) == 10
    assert inspect.iscoroutinefunction(_ToyClient().double)
    assert not inspect.iscoroutinefunction(facade.double)
    assert inspect.signature(facade.double) == inspect.signature(_ToyClient().double)
    assert facade.double.__doc__ == "Twice ``x``, after one event-loop turn."
    assert (facade.latest(), facade.waited) == ("state", 1)
    assert (_ToyClient().latest(), facade.waited) == ("state", 1)
