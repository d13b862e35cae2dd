"""The control API's bearer token (``pymotoros sim --token``), walked over the whole route
table, the WebSocket feed, the open health endpoints, and the CLI's refusal to serve the
control API beyond loopback without a token (issue 23, item 5)."""

from __future__ import annotations

import asyncio
import json
import re
from collections.abc import AsyncIterator
from dataclasses import replace
from typing import Any

import httpx
import pytest
import websocket
from click.testing import CliRunner
from fastapi import FastAPI
from fastapi.routing import APIRoute
from starlette.routing import WebSocketRoute

from pymotoros.cli.main import cli
from pymotoros.controller import VirtualController
from pymotoros.runtime.access import guarded, loopback_or_token
from pymotoros.runtime.app import SimulatorApp

from .support import LOCAL

TOKEN = "s3cret-token-of-the-tests"  # noqa: S105 - a test token (16+ characters)
WS_TIMEOUT_S = 10.0


@pytest.fixture
async def guarded_sim(controller: VirtualController) -> AsyncIterator[SimulatorApp]:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0, token=TOKEN)) as sim:
        yield sim


def http_app(sim: SimulatorApp) -> FastAPI:
    """The FastAPI app the simulator serves (its route table)."""
    assert sim._http is not None
    app = sim._http.config.app
    assert isinstance(app, FastAPI)
    return app


def concrete(path: str) -> str:
    """A route's path with every parameter filled in (``{address}`` -> 1)."""
    return re.sub(r"\{[^}]+\}", "1", path)


def ws_status(url: str, **options: Any) -> int | str:
    """The handshake's HTTP status when refused, else the first document's keys."""
    try:
        ws = websocket.create_connection(url, timeout=WS_TIMEOUT_S, **options)
    except websocket.WebSocketBadStatusException as exc:
        return int(exc.status_code)
    try:
        return ",".join(sorted(json.loads(ws.recv())))
    finally:
        ws.close()


async def test_every_api_route_and_metrics_need_the_token(guarded_sim: SimulatorApp) -> None:
    app = http_app(guarded_sim)
    routes = [r for r in app.routes if isinstance(r, APIRoute) and guarded(r.path)]
    assert len(routes) > 15  # the whole table, not a sample
    assert any(r.path == "/metrics" for r in routes)
    base = f"http://127.0.0.1:{guarded_sim.ports.http}"
    async with httpx.AsyncClient(base_url=base, timeout=10) as client:
        for route in routes:
            path = concrete(route.path)
            for method in sorted(route.methods - {"HEAD"}):
                for headers in ({}, {"Authorization": "Bearer wrong"}, {"Authorization": TOKEN}):
                    r = await client.request(method, path, headers=headers, json={})
                    assert r.status_code == 401, (method, path, headers, r.status_code)
                    assert r.headers["WWW-Authenticate"] == "Bearer"
                    assert "--token" in r.json()["error"]
                r = await client.request(
                    method, path, headers={"Authorization": f"Bearer {TOKEN}"}, json={}
                )
                assert r.status_code != 401, (method, path, r.text)


async def test_open_routes_stay_open(guarded_sim: SimulatorApp) -> None:
    base = f"http://127.0.0.1:{guarded_sim.ports.http}"
    async with httpx.AsyncClient(base_url=base, timeout=10) as client:
        assert (await client.get("/healthz")).json() == {"status": "ok"}
        ready = await client.get("/readyz")
        assert ready.status_code == 200
        assert ready.json()["motoros_listening"] is True
        page = await client.get("/")
        assert page.status_code == 200
        assert '<script src="/pendant/access.js"></script>' in page.text
        script = await client.get("/pendant/access.js")
        assert script.status_code == 200
        assert "sessionStorage" in script.text
        assert "Authorization" in script.text


async def test_the_state_feed_needs_the_token(guarded_sim: SimulatorApp) -> None:
    app = http_app(guarded_sim)
    feeds = [r.path for r in app.routes if isinstance(r, WebSocketRoute)]
    assert feeds == ["/ws/state"]
    url = f"ws://127.0.0.1:{guarded_sim.ports.http}/ws/state"
    assert await asyncio.to_thread(ws_status, url) == 401
    assert await asyncio.to_thread(ws_status, url + "?access_token=wrong") == 401
    keys = await asyncio.to_thread(ws_status, url + f"?access_token={TOKEN}")
    assert "tick" in str(keys).split(",")
    keys = await asyncio.to_thread(ws_status, url, header=[f"Authorization: Bearer {TOKEN}"])
    assert "tick" in str(keys).split(",")


async def test_without_a_token_nothing_is_guarded(controller: VirtualController) -> None:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as sim:
        base = f"http://127.0.0.1:{sim.ports.http}"
        async with httpx.AsyncClient(base_url=base, timeout=10) as client:
            assert (await client.get("/api/state")).status_code == 200
            assert (await client.get("/metrics")).status_code == 200


def test_the_control_api_beyond_loopback_needs_a_token() -> None:
    result = CliRunner().invoke(cli, ["sim", "--host", "0.0.0.0", "--http-port", "0"])
    assert result.exit_code == 2
    assert "--token" in result.output
    assert "--insecure-http" in result.output
    assert loopback_or_token("0.0.0.0", "t", insecure=False) is None
    assert loopback_or_token("0.0.0.0", None, insecure=True) is None
    assert "--token" in str(loopback_or_token("10.0.0.5", None, insecure=False))


def test_the_token_can_come_from_the_environment() -> None:
    result = CliRunner().invoke(
        cli,
        ["sim", "--host", "0.0.0.0", "--http-port", "0", "--robot", "nope"],
        env={"PYMOTOROS_TOKEN": TOKEN},
    )
    # past the access check: it fails later, on the unknown robot (a usage error naming it)
    assert "--token" not in result.output
    assert "nope" in result.output
