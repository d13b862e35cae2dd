"""SimulatorApp: ports, readiness, ordered idempotent shutdown, crashes, slot rules."""

from __future__ import annotations

import asyncio
from dataclasses import replace

import pytest

from pymotoros.controller import VirtualController, default_cell
from pymotoros.controller.scenario import parse_scenario
from pymotoros.protocol.constants import Port
from pymotoros.protocol.messages import Ping, PingReply
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.connections import AdmissionKind, SlotTable
from pymotoros.runtime.tcp import is_loopback

from .fake_controller import BrokenAtTick3
from .peer import Peer
from .support import LOCAL


async def test_ports_are_chosen_by_the_os_and_distinct(app: SimulatorApp) -> None:
    ports = app.ports
    assert len({ports.motion, ports.state, ports.io}) == 3
    assert 0 not in (ports.motion, ports.state, ports.io)
    assert ports.http is None
    assert app.ready.is_set()


async def test_stop_closes_clients_and_is_idempotent(controller: VirtualController) -> None:
    sim = SimulatorApp(controller, LOCAL)
    async with sim:
        motion = await Peer.connect(sim.ports.motion, Port.MOTION)
        state = await Peer.connect(sim.ports.state, Port.STATE)
        assert isinstance(await motion.request(Ping()), PingReply)
        await state.frame()
        await sim.stop()
        await sim.stop()
        assert await motion.is_closed_by_server()
        async with asyncio.timeout(5.0):
            while await state.reader.read(4096):
                pass
        with pytest.raises(OSError):
            await asyncio.open_connection("127.0.0.1", sim.ports.motion)
        await motion.close()
        await state.close()
    assert controller.read_io_bit(11124).value == 0  # OT#893: no motion connection


async def test_serve_can_be_cancelled(controller: VirtualController) -> None:
    sim = SimulatorApp(controller, LOCAL)
    task = asyncio.create_task(sim.serve())
    async with asyncio.timeout(5.0):
        await sim.ready.wait()
    peer = await Peer.connect(sim.ports.motion, Port.MOTION)
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert await peer.is_closed_by_server()
    await peer.close()


async def test_a_crashing_tick_stops_everything_and_propagates() -> None:
    sim = SimulatorApp(BrokenAtTick3(), LOCAL)

    async def run() -> None:
        async with asyncio.timeout(5.0), sim:
            await sim.wait_stopped()

    with pytest.raises(ExceptionGroup) as info:
        await run()
    assert info.group_contains(RuntimeError, match="controller bug")


async def test_port_in_use_is_an_oserror(app: SimulatorApp) -> None:
    clash = SimulatorApp(VirtualController(), replace(LOCAL, motion_port=app.ports.motion))
    with pytest.raises(OSError, match="in use"):
        await clash.__aenter__()


def test_slot_table_rules() -> None:
    table: SlotTable[str] = SlotTable(2)
    assert table.admit("a", motion_queued=True).kind is AdmissionKind.ACCEPT
    assert table.admit("b", motion_queued=False).slot == 1
    assert table.admit("c", motion_queued=True).kind is AdmissionKind.REFUSE
    replace = table.admit("d", motion_queued=False)
    assert (replace.kind, replace.slot, replace.evicted) == (AdmissionKind.REPLACE, 0, "a")
    assert table.occupants() == ["d", "b"]
    assert table.release("a") is False
    assert table.release("b") is True
    assert len(table) == 1


@pytest.mark.parametrize(
    ("host", "loopback"),
    [
        ("127.0.0.1", True),
        ("::1", True),
        ("localhost", True),
        ("0.0.0.0", False),
        ("10.1.2.3", False),
    ],
)
def test_is_loopback(host: str, loopback: bool) -> None:
    assert is_loopback(host) is loopback


async def test_a_scenarios_drop_motion_closes_the_motion_connection_of_an_app_for_a_cell() -> None:
    """``SimulatorApp.for_cell`` builds the controller with the motion server's client set
    as its motion link: the scenario's drop_motion reaches the TCP connection."""
    sim = SimulatorApp.for_cell(default_cell(), LOCAL)
    async with sim:
        motion = await Peer.connect(sim.ports.motion, Port.MOTION)
        assert isinstance(await motion.request(Ping()), PingReply)
        assert sim.controller.read_io_bit(11124).value == 1  # OT#893: motion connected
        sim.controller.load_scenario(
            parse_scenario({"events": [{"at": 0.0, "action": "drop_motion"}]})
        )
        assert await motion.is_closed_by_server()
        assert [f.error for f in sim.controller.fired_events] == [""]
        await motion.close()


async def test_drop_motion_of_a_controller_built_without_a_motion_link_says_why(
    controller: VirtualController,
) -> None:
    """A controller built elsewhere reaches no motion server: drop_motion is refused with
    the reason and what builds one with a link (the control API answers it 400)."""
    async with SimulatorApp(controller, LOCAL) as sim:
        motion = await Peer.connect(sim.ports.motion, Port.MOTION)
        assert isinstance(await motion.request(Ping()), PingReply)
        with pytest.raises(ValueError, match=r"no motion server .*SimulatorApp\.for_cell"):
            controller.drop_motion()
        assert isinstance(await motion.request(Ping()), PingReply)  # still connected
        await motion.close()
