"""PFL and FSU driven over the control API, observed on the motion port (raw sockets)."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator, Callable
from dataclasses import replace
from functools import partial

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.protocol.constants import MotionCommand, NotReadySubcode, Port, ResultCode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionReply, RobotStatus
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.clock import ManualClock

from . import support
from .peer import Peer, ctrl
from .support import LOCAL, virtual_time

MAX_STATE_MESSAGES = 2000
"""State messages read at most while waiting for a ROBOT_STATUS (about 12 s of cycles)."""

OK = (ResultCode.SUCCESS, 0)


until = partial(support.until, timeout_s=20.0)


@pytest.fixture(params=["real time", "virtual time"])
async def sim(
    controller: VirtualController, request: pytest.FixtureRequest
) -> AsyncIterator[SimulatorApp]:
    """The simulator with its control API, on the real clock or on virtual time."""
    clock = ManualClock() if request.param == "virtual time" else None
    async with (
        SimulatorApp(controller, replace(LOCAL, http_port=0), clock=clock) as app,
        contextlib.AsyncExitStack() as stack,
    ):
        if clock is not None:
            await stack.enter_async_context(virtual_time(clock))
        yield app


async def robot_status(peer: Peer, what: str, condition: Callable[[RobotStatus], bool]) -> None:
    """Read the state stream until a ROBOT_STATUS satisfies ``condition`` (bounded)."""
    for _ in range(MAX_STATE_MESSAGES):
        message = await peer.message()
        if isinstance(message, RobotStatus) and condition(message):
            return
    pytest.fail(f"no ROBOT_STATUS with {what} in {MAX_STATE_MESSAGES} state messages")


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
        state = await Peer.connect(sim.ports.state, Port.STATE)
        await robot_status(
            state,
            "in_motion 0, motion_possible 0, no error",
            lambda s: (s.in_motion, s.motion_possible, s.in_error) == (0, 0, 0),
        )
        await state.close()
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
        assert r.status_code == 200
        assert r.json()["fsu"] == {"joint_speed_pct": 50, "tcp_speed_mm_s": 250}
        r = await api.post("/api/fsu", json={"tcp_speed_mm_s": -1})
        assert r.status_code in (400, 422)
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


async def _move_ticks(sim: SimulatorApp, fsu_pct: int | None) -> tuple[int, tuple[int, ...]]:
    """Ticks of a 1.5 s move of every joint at 80 % speed; FSU switched 0.4 s into it."""
    controller = sim.controller
    assert isinstance(controller, VirtualController)
    peer = await Peer.connect(sim.ports.motion, Port.MOTION)
    assert await ctrl(peer, MotionCommand.START_TRAJ_MODE) == OK
    here = list(controller.snapshot().groups[0].command_rad)
    speed = [0.8 * v for v in controller.motoros.axes[0].max_speed[:6]]
    goal = [h + 1.5 * s * 0.5 for h, s in zip(here, speed, strict=True)]
    start = JointTrajPtFull.for_joints(0, 0, 0.0, here, [0.0] * 6)
    end = JointTrajPtFull.for_joints(0, 1, 1.5, goal, [0.0] * 6)
    assert await peer.request(start) == MotoMotionReply(0, 0, 14, 0, 0)
    assert await peer.request(end) == MotoMotionReply(0, 1, 14, 0, 0)
    await until(sim, "moving", controller.has_queued_motion)
    t0 = controller.tick_count
    await sim.ticker.wait_ticks(100)
    async with _api(sim) as api:
        body = {"joint_speed_pct": fsu_pct} if fsu_pct is not None else {"off": True}
        assert (await api.post("/api/fsu", json=body)).status_code == 200
    await until(
        sim,
        "every pulse executed",
        lambda: (
            not controller.has_queued_motion()
            and not any(map(any, controller.motoros.unprocessed_pulses))
        ),
        ticks=5000,
    )
    await peer.close()
    return controller.tick_count - t0, controller.snapshot().groups[0].command_pulse


async def test_fsu_switched_mid_trajectory_over_the_wire(sim: SimulatorApp) -> None:
    free_ticks, free_end = await _move_ticks(sim, None)
    controller = sim.controller
    assert isinstance(controller, VirtualController)
    back = await Peer.connect(sim.ports.motion, Port.MOTION)
    assert await ctrl(back, MotionCommand.START_TRAJ_MODE) == OK
    here = list(controller.snapshot().groups[0].command_rad)
    home = JointTrajPtFull.for_joints(0, 0, 0.0, here, [0.0] * 6)
    zero = JointTrajPtFull.for_joints(0, 1, 3.0, [0.0] * 6, [0.0] * 6)
    assert await back.request(home) == MotoMotionReply(0, 0, 14, 0, 0)
    assert await back.request(zero) == MotoMotionReply(0, 1, 14, 0, 0)
    await until(sim, "moving home", controller.has_queued_motion)
    await until(sim, "back home", lambda: not controller.in_motion(), ticks=3000)
    await sim.ticker.wait_ticks(10)
    await back.close()
    slow_ticks, slow_end = await _move_ticks(sim, 30)
    assert slow_end == free_end  # the same end point, pulse for pulse
    assert slow_ticks > 1.3 * free_ticks  # but later
