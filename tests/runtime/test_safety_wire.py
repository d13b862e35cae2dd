"""PFL and FSU driven over the control API, observed on the motion port (raw sockets)."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from dataclasses import replace

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.protocol.constants import MotionCommand, NotReadySubcode, Port, ResultCode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionReply
from pymotoros.runtime.app import SimulatorApp

from .peer import Peer, ctrl
from .support import LOCAL

OK = (ResultCode.SUCCESS, 0)


async def until(app: SimulatorApp, what: str, condition: object, ticks: int = 2000) -> None:
    assert callable(condition)
    async with asyncio.timeout(20.0):
        for _ in range(ticks):
            if condition():
                return
            await app.ticker.wait_ticks(1)
    pytest.fail(f"{what} did not happen within {ticks} ticks")


@pytest.fixture
async def sim(controller: VirtualController) -> AsyncIterator[SimulatorApp]:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as app:
        yield app


def _api(app: SimulatorApp) -> httpx.AsyncClient:
    return httpx.AsyncClient(base_url=f"http://127.0.0.1:{app.ports.http}", timeout=5.0)


async def _start_move(peer: Peer, app: SimulatorApp, seq0: int = 0) -> None:
    assert await ctrl(peer, MotionCommand.START_TRAJ_MODE) == OK
    here = list(app.controller.snapshot().groups[0].command_rad)
    start = JointTrajPtFull.for_joints(0, seq0, 0.0, here, [0.0] * 6)
    end = JointTrajPtFull.for_joints(0, seq0 + 1, 2.0, [here[0] + 0.3, *here[1:]], [0.0] * 6)
    assert await peer.request(start) == MotoMotionReply(0, seq0, 14, 0, 0)
    assert await peer.request(end) == MotoMotionReply(0, seq0 + 1, 14, 0, 0)
    await until(app, "moving", app.controller.has_queued_motion)


@pytest.mark.parametrize("event", ["contact", "clamping"])
async def test_pfl_over_the_wire_5011_then_recovery(sim: SimulatorApp, event: str) -> None:
    peer = await Peer.connect(sim.ports.motion, Port.MOTION)
    controller = sim.controller
    assert isinstance(controller, VirtualController)
    await _start_move(peer, sim)
    await sim.ticker.wait_ticks(50)
    body: dict[str, object] = {"event": event}
    if event == "clamping":
        body["retreat_ms"] = 100
    async with _api(sim) as api:
        r = await api.post("/api/pfl", json=body)
        assert r.status_code == 200, r.text
        assert r.json()["pfl"] == "stop"
        await sim.ticker.wait_ticks(3)  # the status monitor's next 10 ms read
        here = list(controller.snapshot().groups[0].command_rad)
        point = JointTrajPtFull.for_joints(0, 2, 0.0, here, [0.0] * 6)
        reply = await peer.request(point)
        assert isinstance(reply, MotoMotionReply)
        assert (reply.result, reply.subcode) == (ResultCode.NOT_READY, NotReadySubcode.PFL_ACTIVE)
        await until(sim, "PFL clears", lambda: controller.snapshot().pfl == "idle")
        await until(sim, "stands still", lambda: not controller.in_motion())
        assert (await api.get("/api/state")).json()["pfl"] == "idle"
        assert controller.robot_status().in_motion == 0
        # still 5011 until START_TRAJ_MODE; then streaming from where it stands works
        _, sub = await ctrl(peer, MotionCommand.CHECK_MOTION_READY)
        assert sub == NotReadySubcode.PFL_ACTIVE
        await _start_move(peer, sim, seq0=0)
        # standing still: a contact is refused with a reason
        await until(sim, "done", lambda: not controller.in_motion(), ticks=3000)
        r = await api.post("/api/pfl", json={"event": "contact"})
        assert r.status_code == 400
        assert "stands still" in r.json()["error"]
    await peer.close()


async def test_fsu_over_the_control_api(sim: SimulatorApp) -> None:
    async with _api(sim) as api:
        r = await api.post("/api/fsu", json={"joint_speed_pct": 50})
        assert r.status_code == 200
        assert r.json()["fsu"] == {"joint_speed_pct": 50, "tcp_speed_mm_s": None}
        r = await api.post("/api/fsu", json={"tcp_speed_mm_s": 250})
        assert r.status_code == 400
        assert "kinematics" in r.json()["error"]
        r = await api.post("/api/fsu", json={"joint_speed_pct": 0})
        assert r.status_code == 422
        r = await api.post("/api/fsu", json={"off": True})
        assert r.json()["fsu"] == {"joint_speed_pct": None, "tcp_speed_mm_s": None}
        r = await api.post("/api/pfl", json={"event": "contact", "retreat_ms": 5})
        assert r.status_code == 400
        assert "clamping only" in r.json()["error"]


async def test_scenario_over_the_control_api(sim: SimulatorApp) -> None:
    async with _api(sim) as api:
        bad = await api.post(
            "/api/scenario", json={"events": [{"at": 0.0, "action": "hold", "of": True}]}
        )
        assert bad.status_code == 400
        assert "events[0] (hold).of: unknown key" in bad.json()["error"]
        r = await api.post(
            "/api/scenario",
            json={
                "events": [
                    {"at": 0.0, "action": "hold", "on": True},
                    {"at": 0.0, "action": "fsu", "joint_speed_pct": 40},
                ]
            },
        )
        assert r.status_code == 200
        await sim.ticker.wait_ticks(2)
        doc = (await api.get("/api/state")).json()
        assert doc["hold"] is True
        assert doc["fsu"]["joint_speed_pct"] == 40
        events = doc["events"]
        assert [(e["action"], e.get("on"), e.get("joint_speed_pct")) for e in events] == [
            ("hold", True, None),
            ("fsu", None, 40),
        ]
        assert all(e["t"] > 0 for e in events)
