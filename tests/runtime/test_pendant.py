"""The web pendant: the page and its assets are local, the feed pushes live state with
joint frames, and state-changing requests from other sites are refused (CSRF)."""

from __future__ import annotations

import asyncio
import itertools
import json
import math
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

import httpx
import pytest
import websocket

from pymotoros.controller import VirtualController, signals
from pymotoros.controller.cell import default_cell, load_cell
from pymotoros.controller.scenario import parse_scenario
from pymotoros.kinematics import chain_for
from pymotoros.models.robots import ROBOTS
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.http_api import create_http_app, state_model
from pymotoros.runtime.pendant import (
    FEED_PERIOD_S,
    TICK_STATS_REFRESH_TICKS,
    Captured,
    PendantDocument,
    PendantFeed,
)
from pymotoros.runtime.pendant.document import Skeleton, encode, state_document
from pymotoros.runtime.ticker import TickStats

from .support import LOCAL, STATS

MIN_FEED_HZ = 20.0
"""The issue's floor for live updates."""
WS_TIMEOUT_S = 5.0
"""Generous bound on one WebSocket read (documents come every 40 ms)."""
HTTP_FORBIDDEN = 403
CELLS = Path(__file__).resolve().parents[2] / "examples" / "cells"


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


def _as_json(doc: object) -> object:
    return json.loads(json.dumps(doc))


def _busy(controller: VirtualController) -> VirtualController:
    """A controller with something in every part of the state document."""
    controller.raise_alarm(4107, 3, "from the test")
    controller.raise_error(2020, 1, "an operator error")
    controller.set_fsu(joint_speed_pct=40, tcp_speed_mm_s=None, off=False)
    controller.load_scenario(
        parse_scenario({"events": [{"at": 0.0, "action": "hold", "on": True}]}, source="the test")
    )
    for _ in range(3):
        controller.tick()
    return controller


def _pfl_stop(controller: VirtualController) -> VirtualController:
    """A collaborative robot (PFL on) whose safety unit signals a PFL stop."""
    assert controller.cell.pfl
    controller.force_io(signals.PFL_STOP, 1)
    for _ in range(3):
        controller.tick()
    return controller


STATES = {
    "boot": lambda: VirtualController(),
    "alarms-errors-fsu-events": lambda: _busy(VirtualController()),
    "two-groups": lambda: _busy(VirtualController(cell=load_cell(CELLS / "two_hc10_dx100.toml"))),
    "sda10f": lambda: VirtualController(cell=default_cell(robot="sda10f")),
    "pfl-fsu": lambda: _pfl_stop(
        _busy(VirtualController(cell=load_cell(CELLS / "hc10_yrc1000.toml")))
    ),
}
"""Controller states with something in every part of the document."""


@pytest.mark.parametrize("make", STATES.values(), ids=STATES.keys())
def test_feed_document_is_the_control_apis_state_without_pydantic(make: Any) -> None:
    """The feed builds GET /api/state's document by hand (it runs 25 times a second on
    the loop): as JSON it must be the same document, key for key."""
    controller = make()
    snapshot = controller.snapshot()
    ports = (50240, 50241, None)
    by_hand = state_document(snapshot, STATS, ports)
    by_model = state_model(snapshot, STATS, ports).model_dump_json()
    assert _as_json(by_hand) == json.loads(by_model)
    assert list(by_hand) == list(json.loads(by_model))  # same key order too


def test_pendant_shows_operator_errors_and_eco_off(controller: VirtualController) -> None:
    _busy(controller)
    doc = create_http_app(controller, lambda: STATS).state.pendant_feed.document()
    assert doc["pendant"]["errors"] == [{"code": 2020, "subcode": 1, "text": "an operator error"}]
    assert [a["code"] for a in doc["alarms"]] == [4107]
    assert doc["pendant"]["eco"] is False


def test_pendant_shows_eco_mode(tmp_path: Path) -> None:
    cell = tmp_path / "eco.toml"
    cell.write_text(
        'name = "eco"\n[[groups]]\nrobot = "hc10"\n[initial]\nservo = true\neco = true\n'
    )
    controller = VirtualController(cell=load_cell(cell))
    feed = create_http_app(controller, lambda: STATS).state.pendant_feed
    assert feed.document()["pendant"]["eco"] is True
    controller.set_servo(False)  # servo off ends eco mode
    controller.tick()
    assert feed.document()["pendant"]["eco"] is controller.operator_state.eco is False


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_skeleton_points_are_the_chains_joint_positions(robot: str) -> None:
    """The feed's cheap forward kinematics gives the same positions as
    ``Chain.joint_frames`` at any pose, also when the pose changes back and forth."""
    for group in default_cell(robot=robot).groups:
        chain = chain_for(group)
        skeleton = Skeleton(chain)
        n = chain.num_joints
        poses = [[0.3 * (i + 1) * (-1) ** i for i in range(n)], [0.0] * n]
        for q in poses + poses:
            assert skeleton.points(q) == [f["xyz"] for f in chain.joint_frames(q)]
        with pytest.raises(ValueError, match=f"expected {n} joint values"):
            skeleton.points([0.0] * (n + 1))


def _extensions(url: str, origin: str) -> str:
    ws = websocket.create_connection(
        url,
        timeout=WS_TIMEOUT_S,
        origin=origin,
        header=["Sec-WebSocket-Extensions: permessage-deflate; client_max_window_bits"],
    )
    try:
        ws.recv()
        headers = ws.getheaders() or {}
        return str(headers.get("sec-websocket-extensions", ""))
    finally:
        ws.close()


async def test_feed_is_not_compressed_even_when_the_browser_offers_it(
    controller: VirtualController,
) -> None:
    """Browsers offer permessage-deflate; compressing every document for every tab would
    cost the interpolation loop CPU for nothing on a local link."""
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as sim:
        base = f"127.0.0.1:{sim.ports.http}"
        extensions = await asyncio.to_thread(_extensions, f"ws://{base}/ws/state", f"http://{base}")
        assert "deflate" not in extensions


class _Ticks:
    """A stand-in for ``Ticker.wait_ticks`` that the test advances tick by tick."""

    def __init__(self) -> None:
        self.count = 0
        self.waits = 0
        self._waiters: list[tuple[int, asyncio.Future[None]]] = []

    async def after(self, n: int) -> None:
        self.waits += 1
        future = asyncio.get_running_loop().create_future()
        self._waiters.append((self.count + n, future))
        await future

    async def tick(self) -> None:
        self.count += 1
        for target, future in list(self._waiters):
            if target <= self.count:
                self._waiters.remove((target, future))
                future.set_result(None)
        for _ in range(LOOP_TURNS_PER_TICK):  # let every woken task run to its next wait
            await asyncio.sleep(0)


LOOP_TURNS_PER_TICK = 20
"""Event-loop turns after each virtual tick: more than the feed's tasks need to settle."""


class _Tab:
    """A WebSocket that records on which tick each document was sent."""

    def __init__(self, ticks: _Ticks, events: list[tuple[int, str]], name: str) -> None:
        self._ticks, self._events, self._name = ticks, events, name

    async def accept(self) -> None:
        return None

    async def send_text(self, text: str) -> None:
        assert json.loads(text)["groups"]
        self._events.append((self._ticks.count, self._name))


async def test_feed_work_is_spread_over_the_ticks_of_its_period(
    controller: VirtualController,
) -> None:
    """Capture after one tick, render and encode after the next, then one tab per tick:
    no tick is followed by more than one piece of the feed's work (module docstring)."""
    ticks = _Ticks()
    events: list[tuple[int, str]] = []

    class Recording(PendantDocument):
        def capture(self) -> Captured:
            events.append((ticks.count, "capture"))
            return super().capture()

        def render(self, captured: Captured) -> dict[str, Any]:
            events.append((ticks.count, "render"))
            return super().render(captured)

    period = round(FEED_PERIOD_S * 1000 / controller.period_ms)
    waiting_at_publish: list[int] = []

    class Feed(PendantFeed):
        def _publish(self, text: str) -> None:
            waiting_at_publish.append(len(self._waiting))
            super()._publish(text)

    feed = Feed(Recording(controller, lambda: STATS), after_ticks=ticks.after, period_ticks=period)
    tabs = [
        asyncio.create_task(feed.serve(_Tab(ticks, events, f"tab{i}")))  # type: ignore[arg-type]
        for i in range(3)
    ]
    await asyncio.sleep(0)
    for _ in range(3 * period):
        await ticks.tick()
    for task in tabs:
        task.cancel()
    await asyncio.gather(*tabs, return_exceptions=True)
    captures = [t for t, what in events if what == "capture"]
    assert len(captures) >= 3
    assert {b - a for a, b in itertools.pairwise(captures)} == {period}
    for start in captures[:-1]:
        in_period = sorted((t, w) for t, w in events if start <= t < start + period)
        assert in_period == [
            (start, "capture"),
            (start + 1, "render"),
            (start + 2, "tab0"),
            (start + 3, "tab1"),
            (start + 4, "tab2"),
        ]
    # each wake-up costs the loop: the feed waits twice per period, each tab once (its
    # slot one period on), plus each tab's first wait for its slot
    periods = len(captures)
    assert ticks.waits <= periods * (2 + len(tabs)) + len(tabs)
    # after the first document no tab waits for a publication: it is woken only by its slot
    assert waiting_at_publish[0] == len(tabs)
    assert set(waiting_at_publish[1:]) == {0}


SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


async def test_page_loads_a_toml_scenario_file_as_the_cli_does(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    """The "Load scenario" button sends the file's text; the simulator parses it the way
    ``pymotoros sim --scenario`` does, so the example files work as they are."""
    for path in sorted(SCENARIOS.glob("*.toml")):
        r = await api.post(
            "/api/pendant/scenario", json={"name": path.name, "toml": path.read_text()}
        )
        assert r.status_code == 200, (path.name, r.text)
    toml = '[[events]]\nat = 0.0\naction = "hold"\non = true\n'
    r = await api.post("/api/pendant/scenario", json={"name": "hold.toml", "toml": toml})
    assert r.status_code == 200
    assert "pendant" in r.json()
    controller.tick()
    assert controller.snapshot().hold is True


@pytest.mark.parametrize(
    ("toml", "message"),
    [
        ("[[events]\n", "hold.toml: not valid TOML"),
        ('[[events]]\nat = 0.0\naction = "fly"\n', "hold.toml: events[0]"),
        ("title = 1\n", "hold.toml: title: unknown key"),
    ],
)
async def test_a_wrong_scenario_file_is_refused_with_its_name_and_the_reason(
    api: httpx.AsyncClient, controller: VirtualController, toml: str, message: str
) -> None:
    r = await api.post("/api/pendant/scenario", json={"name": "hold.toml", "toml": toml})
    assert r.status_code == 400
    assert message in r.json()["error"]
    r = await api.post(
        "/api/pendant/scenario",
        json={"name": "x.toml", "toml": "[[events]]\n"},
        headers={"Origin": "http://evil.example"},
    )
    assert r.status_code == HTTP_FORBIDDEN


def test_feed_recomputes_the_loops_percentiles_once_a_second_with_an_exact_tick_count(
    controller: VirtualController,
) -> None:
    """``Ticker.stats`` costs about 0.25 ms (the whole lateness window is partitioned):
    the feed asks for it once per TICK_STATS_REFRESH_TICKS ticks and advances the count
    itself in between."""
    calls: list[int] = []

    def stats() -> TickStats:
        calls.append(controller.snapshot().tick_count)
        return replace(STATS, count=controller.snapshot().tick_count)

    document = PendantDocument(controller, stats)
    period = round(FEED_PERIOD_S * 1000 / controller.period_ms)
    for _ in range(3 * TICK_STATS_REFRESH_TICKS // period):
        doc = document()
        assert doc["tick"]["count"] == controller.snapshot().tick_count
        for _ in range(period):
            controller.tick()
    assert len(calls) == 3
    assert [b - a for a, b in itertools.pairwise(calls)] == [TICK_STATS_REFRESH_TICKS] * 2


@pytest.mark.parametrize("make", STATES.values(), ids=STATES.keys())
def test_feed_encodes_the_document_as_the_stdlib_json_would(make: Any) -> None:
    """The feed encodes with orjson (a fraction of the stdlib's time on the loop): what
    the tabs parse must be what ``json.dumps``'s text parses to, every float bit for bit
    and every key in its place (only an exponent's spelling may differ: 1e-6, 1e-06)."""
    controller = make()
    for _ in range(2):
        doc = create_http_app(controller, lambda: STATS).state.pendant_feed.document()
        by_orjson = json.loads(encode(doc))
        by_stdlib = json.loads(json.dumps(doc))
        assert by_orjson == by_stdlib
        assert json.dumps(by_orjson) == json.dumps(by_stdlib)  # key order, float bits
        for _ in range(25):  # moving or not, the floats change
            controller.tick()


def test_pfl_and_fsu_cell_document() -> None:
    controller = STATES["pfl-fsu"]()
    doc = create_http_app(controller, lambda: STATS).state.pendant_feed.document()
    assert doc["pfl"] != "off"
    assert doc["fsu"]["joint_speed_pct"] == 40


def test_pendant_reads_motoros_outputs_as_single_bits(controller: VirtualController) -> None:
    """OT#889..896 are read as one IO group; each must be the bit ``read_io_bit`` gives."""
    document = create_http_app(controller, lambda: STATS).state.pendant_feed.document
    for pattern in (0b1010_0101, 0b0101_1010, 0):
        for i in range(8):
            controller.io.set(11120 + i, (pattern >> i) & 1)
        outputs = document()["pendant"]["outputs"]
        assert [o["value"] for o in outputs] == [
            controller.read_io_bit(11120 + i).value for i in range(8)
        ]
        assert [o["value"] for o in outputs] == [(pattern >> i) & 1 for i in range(8)]
