"""Start-up checks over the network: MotoROS's ports refuse connections until it starts."""

from __future__ import annotations

import asyncio
import contextlib
from dataclasses import replace

import httpx
import pytest

from pymotoros.controller import VirtualController, cell_from_dict
from pymotoros.protocol.constants import MotionCommand, Port, ResultCode
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.clock import ManualClock

from .peer import Peer, ctrl
from .support import LOCAL, virtual_time


async def refused(port: int) -> bool:
    try:
        async with asyncio.timeout(5.0):
            _, writer = await asyncio.open_connection("127.0.0.1", port)
    except ConnectionRefusedError:
        return True
    writer.close()
    await writer.wait_closed()
    return False


def controller(**ctrl_keys: object) -> VirtualController:
    return VirtualController(cell_from_dict({"controller": dict(ctrl_keys)}))


@pytest.mark.parametrize("real_time", [True, False])
async def test_fatal_8003_ports_never_listen_http_says_why(real_time: bool) -> None:
    clock = None if real_time else ManualClock()
    vc = controller(software="YAS2.70.00-00")
    async with (
        SimulatorApp(vc, replace(LOCAL, http_port=0), clock=clock) as sim,
        contextlib.AsyncExitStack() as stack,
    ):
        if clock is not None:
            await stack.enter_async_context(virtual_time(clock))
        assert not sim.motoros_listening
        for port in (sim.ports.motion, sim.ports.state, sim.ports.io):
            assert await refused(port)
        async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{sim.ports.http}") as api:
            doc = (await api.get("/api/state")).json()
            assert doc["ports"] == {"motion": None, "state": None, "io": None}
            assert doc["alarms"] == [
                {"code": 8003, "subcode": 8, "text": "PFL invalid controller version"}
            ]
            assert "waiting for RESET" in doc["motoros"]
            doc = (await api.post("/api/reset")).json()
            await sim.ticker.wait_ticks(30)
            doc = (await api.get("/api/state")).json()
            assert "halted" in doc["motoros"]
            assert "YAS2.80" in doc["motoros"]
            assert doc["ports"]["motion"] is None
        assert await refused(sim.ports.motion)


async def test_warning_8003_ports_listen_after_reset() -> None:
    vc = controller(parameters={"S2C1119": 1})
    async with SimulatorApp(vc, replace(LOCAL, http_port=0)) as sim:
        assert await refused(sim.ports.motion)
        async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{sim.ports.http}") as api:
            await api.post("/api/reset")
            async with asyncio.timeout(10.0):
                while not sim.motoros_listening:
                    await sim.ticker.wait_ticks(5)
            doc = (await api.get("/api/state")).json()
            assert doc["ports"] == {
                "motion": sim.ports.motion,
                "state": sim.ports.state,
                "io": sim.ports.io,
            }
        peer = await Peer.connect(sim.ports.motion, Port.MOTION)
        assert await ctrl(peer, MotionCommand.CHECK_MOTION_READY) != (ResultCode.SUCCESS, 0)
        assert await ctrl(peer, MotionCommand.START_TRAJ_MODE) == (ResultCode.SUCCESS, 0)
        await peer.close()


@pytest.mark.parametrize(
    ("keys", "subcode", "fatal"),
    [
        ({"parameters": {"RS000": 1}}, 1, False),
        ({"parameters": {"S2C541": 1}}, 2, False),
        ({"parameters": {"S2C542": 1}}, 3, False),
        ({"parameters": {"S2C1100": 0}}, 4, True),
        ({"parameters": {"S2C1103": 0}}, 5, True),
        ({"model": "yrc1000micro", "parameters": {"S2C1117": 0}}, 6, True),
        ({"parameters": {"S2C1119": 3}}, 7, False),
        ({"software": "YAS2.79.00-00"}, 8, True),
        ({"validation_code": 9}, 9, True),
        ({"validation_code": 10}, 10, True),
        ({"conveyor_tracking": True}, 11, True),
        ({"validation_code": 104}, 104, True),
    ],
)
async def test_every_8003_subcode_on_the_ports(
    keys: dict[str, object], subcode: int, fatal: bool
) -> None:
    clock = ManualClock()
    vc = controller(**keys)
    async with (
        SimulatorApp(vc, replace(LOCAL, http_port=0), clock=clock) as sim,
        virtual_time(clock),
    ):
        assert [(a.code, a.subcode) for a in vc.snapshot().alarms] == [(8003, subcode)]
        assert await refused(sim.ports.motion)
        vc.reset()
        await sim.ticker.wait_ticks(60)  # the runtime looks every 25 ticks
        assert sim.motoros_listening is (not fatal)
        for port in (sim.ports.motion, sim.ports.state, sim.ports.io):
            assert await refused(port) is fatal


async def test_an_alarm_at_boot_holds_the_ports_until_reset() -> None:
    clock = ManualClock()
    vc = VirtualController(cell_from_dict({"initial": {"alarms": [{"code": 4100}]}}))
    async with (
        SimulatorApp(vc, replace(LOCAL, http_port=0), clock=clock) as sim,
        virtual_time(clock),
    ):
        await sim.ticker.wait_ticks(1000)  # 4 s: still held back
        assert await refused(sim.ports.motion)
        vc.reset()
        reset_tick = vc.tick_count
        async with asyncio.timeout(10.0):
            while not sim.motoros_listening:
                await sim.ticker.wait_ticks(5)
        # the next 2.5 s check after the reset, then the runtime's next look (25 ticks)
        assert vc.tick_count - reset_tick <= 2500 // vc.period_ms + 30
        assert not await refused(sim.ports.motion)
