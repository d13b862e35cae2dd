"""The web pendant: the page and its assets are local, the feed pushes live state with
joint frames, and state-changing requests from other sites are refused (CSRF)."""

from __future__ import annotations

import asyncio
import json
import math
import re
from collections.abc import AsyncIterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import httpx
import pytest
import websocket

from pymotoros.controller import VirtualController
from pymotoros.controller.cell import default_cell, load_cell
from pymotoros.kinematics import chain_for
from pymotoros.models.robots import ROBOTS
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.http_api import create_http_app
from pymotoros.runtime.pendant import FEED_PERIOD_S
from pymotoros.runtime.ticker import LatenessStats, TickStats

from .support import LOCAL

STATS = TickStats(4.0, 1000, 2, 0, 0, LatenessStats(0.05, 0.2, 1.5))
MIN_FEED_HZ = 20.0
"""The issue's floor for live updates."""
WS_TIMEOUT_S = 5.0
"""Generous bound on one WebSocket read (documents come every 40 ms)."""
HTTP_FORBIDDEN = 403
CELLS = Path(__file__).resolve().parents[2] / "examples" / "cells"


@pytest.fixture
async def api(controller: VirtualController) -> AsyncIterator[httpx.AsyncClient]:
    app = create_http_app(controller, lambda: STATS)
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://sim") as client:
        yield client


def test_feed_period_is_at_least_20_hz() -> None:
    assert 1.0 / FEED_PERIOD_S >= MIN_FEED_HZ


async def test_page_and_every_asset_it_references_are_served_locally(
    api: httpx.AsyncClient,
) -> None:
    page = await api.get("/")
    assert page.status_code == 200
    assert "text/html" in page.headers["content-type"]
    assert "E-STOP" in page.text
    urls = re.findall(r"""(?:src|href)\s*=\s*['"]([^'"]+)['"]""", page.text)
    assert "/pendant/pendant.js" in urls
    assert [u for u in urls if re.match(r"(?i)(https?:)?//", u)] == []
    for url in urls:
        assert (await api.get(url)).status_code == 200, url
    script = (await api.get("/pendant/pendant.js")).text
    assert not re.search(r"(?i)https?://", script)
    assert "/ws/state" in script


async def test_pendant_document_has_the_state_and_joint_frames(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    doc = (await api.get("/api/pendant/state")).json()
    state = (await api.get("/api/state")).json()
    assert {k: v for k, v in doc.items() if k not in ("groups", "pendant")} == {
        k: v for k, v in state.items() if k != "groups"
    }
    extra = doc["pendant"]
    # INIT_ROS has not started at boot: MotoROS would answer 5 / 5007 NOT_STARTED
    assert extra["not_ready"]["name"] == controller.motoros.not_ready_reason()[1]
    assert extra["not_ready"]["subcode"] != 0
    assert [o["name"] for o in extra["outputs"]] == [f"OT#{n}" for n in range(889, 897)]
    assert all(set(j) == {"job", "line"} for j in extra["jobs"])
    assert "clients" not in extra  # only the running simulator knows its clients
    group = doc["groups"][0]
    chain = chain_for(controller.cell.groups[0])
    expected = [f["xyz"] for f in chain.joint_frames(group["feedback_rad"])]
    assert group["frames"]["feedback"] == expected
    assert len(group["frames"]["command"]) == chain.num_joints + 3  # flange, tool0, tcp


def _receive(url: str, origin: str | None, count: int) -> list[dict[str, Any]]:
    """Open the feed like a browser tab (blocking client, run in a thread) and read
    ``count`` documents."""
    ws = websocket.create_connection(url, timeout=WS_TIMEOUT_S, origin=origin)
    try:
        return [json.loads(ws.recv()) for _ in range(count)]
    finally:
        ws.close()


async def test_websocket_pushes_live_state(controller: VirtualController) -> None:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as sim:
        url = f"ws://127.0.0.1:{sim.ports.http}/ws/state"
        docs = await asyncio.to_thread(_receive, url, f"http://127.0.0.1:{sim.ports.http}", 30)
        ticks = [d["tick"]["count"] for d in docs]
        assert ticks == sorted(ticks)
        assert ticks[-1] > ticks[0]  # live: the loop advanced between documents
        assert math.isfinite(docs[-1]["groups"][0]["frames"]["feedback"][-1][2])
        assert docs[-1]["pendant"]["clients"] == {"motion": 0, "state": 0, "io": 0}
        async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{sim.ports.http}") as client:
            await client.post("/api/estop", json={"pressed": True})
        docs = await asyncio.to_thread(_receive, url, None, 2)
        assert docs[-1]["estop"] is True


async def test_websocket_from_another_site_is_refused(controller: VirtualController) -> None:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as sim:
        url = f"ws://127.0.0.1:{sim.ports.http}/ws/state"
        with pytest.raises(websocket.WebSocketBadStatusException) as err:
            await asyncio.to_thread(_receive, url, "http://evil.example", 1)
        assert err.value.status_code == HTTP_FORBIDDEN


async def test_cross_site_post_is_refused_and_changes_nothing(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    r = await api.post(
        "/api/estop", json={"pressed": True}, headers={"Origin": "http://evil.example"}
    )
    assert r.status_code == 403
    assert "cross-site" in r.json()["error"]
    assert controller.snapshot().estop is False
    r = await api.post(
        "/api/estop",
        json={"pressed": True},
        headers={"Referer": "http://evil.example/page.html"},
    )
    assert r.status_code == 403
    assert controller.snapshot().estop is False


async def test_same_origin_and_header_less_posts_are_allowed(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    r = await api.post("/api/estop", json={"pressed": True}, headers={"Origin": "http://sim"})
    assert r.status_code == 200
    assert r.json()["estop"] is True
    r = await api.post("/api/estop", json={"pressed": False})  # curl, scripts: no Origin
    assert r.status_code == 200
    assert controller.snapshot().estop is False


async def test_cross_site_get_still_reads(api: httpx.AsyncClient) -> None:
    r = await api.get("/api/state", headers={"Origin": "http://evil.example"})
    assert r.status_code == 200


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_every_built_in_model_has_joint_frames_for_the_3d_view(robot: str) -> None:
    """Every group of every built-in robot (SDA10F: two arms and the torso) is drawn."""
    controller = VirtualController(cell=default_cell(robot=robot))
    app = create_http_app(controller, lambda: STATS)
    doc = app.state.pendant_feed.document()
    assert len(doc["groups"]) == len(controller.cell.groups)
    for group in doc["groups"]:
        frames = group["frames"]
        assert frames is not None, group["name"]
        assert len(frames["feedback"]) == len(group["feedback_rad"]) + 3
        assert frames["command"] == frames["feedback"]  # at rest


def test_multi_group_cell_file_has_frames_per_group() -> None:
    controller = VirtualController(cell=load_cell(CELLS / "two_hc10_dx100.toml"))
    doc = create_http_app(controller, lambda: STATS).state.pendant_feed.document()
    assert [g["name"] for g in doc["groups"]] == ["R1", "R2"]
    assert all(g["frames"] is not None for g in doc["groups"])
