"""One declaration per action, every surface derived from it (issue 19 item 1).

An action declared once, here in the test, is served by the control API with its
OpenAPI schema, is a scenario file's action and is in the pendant's action list, with
the same range check everywhere; and for every declared action, the same value sent
through an HTTP request and through a scenario file is accepted by both or refused by
both with the same words.
"""

from __future__ import annotations

import asyncio
import json
import math
import tomllib
from collections.abc import Iterator
from typing import Any, Final

import httpx
import pytest
from fastapi import FastAPI
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pymotoros.controller import VirtualController
from pymotoros.controller.actions import CONTROL_ACTIONS, ActionSpec, Param
from pymotoros.controller.scenario import parse_scenario
from pymotoros.errors import ConfigError
from pymotoros.runtime.http_api import create_http_app

from .support import STATS

BEACON = ActionSpec(
    "beacon",
    "/api/beacon",
    "Light the cell's beacon: a user alarm 8000 + level.",
    lambda target, p: target.raise_alarm(8000 + p["level"], 0, p["colour"]),
    (
        Param("level", "int", "how urgent", unit="", ge=1, le=5),
        Param("colour", "str", "the lamp", required=False, default="red", choices=("red", "amber")),
    ),
)
"""A new operator action, declared once (nowhere else in the project)."""
WITH_BEACON: Final = (*CONTROL_ACTIONS, BEACON)


class BlockingClient:
    """A blocking client of the control API in process (ASGI, no socket), so Hypothesis
    can drive it example by example."""

    def __init__(self, app: FastAPI, *, raise_server_exceptions: bool = True) -> None:
        self._loop = asyncio.new_event_loop()
        transport = httpx.ASGITransport(app=app, raise_app_exceptions=raise_server_exceptions)
        self._client = httpx.AsyncClient(transport=transport, base_url="http://sim")

    def __enter__(self) -> BlockingClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self._loop.run_until_complete(self._client.aclose())
        self._loop.close()

    def get(self, path: str) -> httpx.Response:
        return self._loop.run_until_complete(self._client.get(path))

    def post(self, path: str, **kwargs: Any) -> httpx.Response:
        return self.request("POST", path, **kwargs)

    def request(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        return self._loop.run_until_complete(self._client.request(method, path, **kwargs))


@pytest.fixture
def beacon_api() -> Iterator[tuple[BlockingClient, VirtualController]]:
    controller = VirtualController()
    app = create_http_app(controller, lambda: STATS, actions=WITH_BEACON)
    with BlockingClient(app) as client:
        yield client, controller


def test_a_new_action_declared_once_is_on_every_surface(
    beacon_api: tuple[BlockingClient, VirtualController],
) -> None:
    client, controller = beacon_api
    # the control API and its OpenAPI schema
    schema = client.get("/openapi.json").json()
    post = schema["paths"]["/api/beacon"]["post"]
    assert post["description"] == BEACON.doc
    ref = post["requestBody"]["content"]["application/json"]["schema"]["$ref"]
    body = schema["components"]["schemas"][ref.rsplit("/", 1)[1]]
    assert body["properties"]["level"]["minimum"] == 1
    assert body["properties"]["level"]["maximum"] == 5
    assert body["properties"]["colour"]["enum"] == ["red", "amber"]
    assert body["required"] == ["level"]
    r = client.post("/api/beacon", json={"level": 3, "colour": "amber"})
    assert r.status_code == 200, r.text
    assert r.json()["alarms"] == [{"code": 8003, "subcode": 0, "text": "amber"}]
    # the pendant's action list: the path its button calls, and the same bounds
    listed = {a["name"]: a for a in client.get("/api/pendant/actions").json()}
    assert listed["beacon"]["path"] == "/api/beacon"
    assert listed["beacon"]["params"][0]["bounds"] == "1..5"
    assert listed["estop"]["path"] == "/api/estop"
    # the scenario file format, through the pendant's "Load scenario" and in Python
    toml = '[[events]]\nat = 0.0\naction = "beacon"\nlevel = 5\n'
    r = client.post("/api/pendant/scenario", json={"name": "b.toml", "toml": toml})
    assert r.status_code == 200, r.text
    controller.tick()
    assert [a.code for a in controller.snapshot().alarms] == [8003, 8005]
    with pytest.raises(ConfigError, match="must be one of"):  # not declared there
        parse_scenario(tomllib.loads(toml))
    r = client.post("/api/scenario", json={"events": [{"at": 0.0, "action": "beacon",
                                                       "level": 1}]})  # fmt: skip
    assert r.status_code == 200, r.text
    controller.tick()
    assert [a.code for a in controller.snapshot().alarms] == [8003, 8005, 8001]
    # the same range check everywhere, with the same words
    words = "level: must lie in 1..5, not 6"
    r = client.post("/api/beacon", json={"level": 6})
    assert r.status_code == 422
    assert r.json()["error"] == f"POST /api/beacon: {words}"
    with pytest.raises(ConfigError) as info:
        parse_scenario(tomllib.loads(toml.replace("5", "6")), actions=WITH_BEACON)
    assert str(info.value) == f"<scenario>: events[0] (beacon).{words}"
    bad = toml.replace("5", "6")
    r = client.post("/api/pendant/scenario", json={"name": "b.toml", "toml": bad})
    assert r.status_code == 400
    assert r.json()["error"].endswith(f"b.toml: events[0] (beacon).{words}")


def _not_flat(box: list[float]) -> str | None:
    return "a box needs a thickness: its z must be at least 1 mm" if box[2] < 0.001 else None


PLACE = ActionSpec(
    "place",
    "/api/place",
    "Put a box in the cell (issue 21's obstacles are declared like this).",
    lambda target, p: target.raise_alarm(8100, 0, f"{p['name']} at {p['xyz']}"),
    (
        Param("name", "str", "the obstacle's name", max_length=32),
        Param("box", "numbers", "full sizes x, y, z", unit="m", length=3, gt=0, check=_not_flat),
        Param("xyz", "numbers", "centre in base_link", unit="m", length=3, ge=-5, le=5),
    ),
)
"""An action with structured parameters (arrays of numbers with a length and bounds)."""


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ({"box": [1, 1], "xyz": [0, 0, 0]}, "box: must hold 3 numbers, not 2"),
        ({"box": [1, 0, 1], "xyz": [0, 0, 0]}, "box: [1] must be > 0 m, not 0"),
        ({"box": [1, 1, 0.0001], "xyz": [0, 0, 0]}, "box: a box needs a thickness"),
        ({"box": [1, 1, 1], "xyz": [0, 9, 0]}, "xyz: [1] must lie in -5..5 m, not 9"),
        ({"box": [1, 1, 1], "xyz": [0, True, 0]}, "xyz: must be an array of numbers"),
    ],
)
def test_a_structured_parameter_is_checked_alike_everywhere(
    body: dict[str, object], words: str
) -> None:
    app = create_http_app(VirtualController(), lambda: STATS, actions=(*CONTROL_ACTIONS, PLACE))
    event = {"at": 0, "action": "place", "name": "table", **body}
    with BlockingClient(app) as client:
        r = client.post("/api/place", json={"name": "table", **body})
        assert r.status_code == 422
        assert r.json()["error"].startswith(f"POST /api/place: {words}")
        ok = client.post("/api/place", json={"name": "table", "box": [1, 1, 1], "xyz": [0, 0, 0]})
        assert ok.json()["alarms"][0]["text"] == "table at [0.0, 0.0, 0.0]"
        schema = client.get("/openapi.json").json()["components"]["schemas"]["PlaceBody"]
        assert schema["properties"]["xyz"]["minItems"] == 3
        assert schema["properties"]["xyz"]["items"]["maximum"] == 5
    with pytest.raises(ConfigError) as info:
        parse_scenario({"events": [event]}, actions=(*CONTROL_ACTIONS, PLACE))
    assert f"events[0] (place).{words}" in str(info.value)


REMOVE = ActionSpec(
    "remove",
    "/api/things/{name}",
    "Take a thing out of the cell by name (issue 21's DELETE /api/workspace/NAME).",
    lambda target, p: target.raise_alarm(8200 + p["slot"], 0, f"removed {p['name']}"),
    (
        Param("name", "str", "the thing's name", max_length=8),
        Param("slot", "int", "where it stood", required=False, default=0, ge=0, le=9),
    ),
    method="DELETE",
)
"""An action whose key parameter is in the path, with the DELETE method."""


def test_a_parameter_in_the_path_is_checked_like_any_other() -> None:
    actions = (*CONTROL_ACTIONS, REMOVE)
    app = create_http_app(VirtualController(), lambda: STATS, actions=actions)
    with BlockingClient(app) as client:
        r = client.request("DELETE", "/api/things/table", json={"slot": 3})
        assert r.status_code == 200, r.text
        assert r.json()["alarms"] == [{"code": 8203, "subcode": 0, "text": "removed table"}]
        r = client.request("DELETE", "/api/things/longtable")
        words = "name: must be at most 8 characters, not 9"
        assert (r.status_code, r.json()["error"]) == (422, f"DELETE /api/things/longtable: {words}")
        op = client.get("/openapi.json").json()["paths"]["/api/things/{name}"]["delete"]
        assert [p["name"] for p in op["parameters"]] == ["name"]
        listed = {a["name"]: a for a in client.get("/api/pendant/actions").json()}
        assert (listed["remove"]["method"], listed["remove"]["path"]) == ("DELETE", REMOVE.path)
    event = {"at": 0, "action": "remove", "name": "longtable"}
    with pytest.raises(ConfigError, match=f"{words}$"):
        parse_scenario({"events": [event]}, actions=actions)


SLOT = ActionSpec(
    "slot",
    "/api/slots/{n}/{x}",
    "Two numbers in the path and one in the body.",
    lambda target, p: target.raise_alarm(8300 + p["n"], 0, f"x={p['x']} y={p['y']}"),
    (
        Param("n", "int", "a slot", ge=0, le=9),
        Param("x", "number", "where in it", unit="m", ge=-1, le=1),
        Param("y", "number", "how high", unit="m", ge=0, le=2),
    ),
    method="PUT",
)
"""An action with several typed parameters in the path and a required body."""


def test_parameters_in_the_path_keep_their_order_type_and_words() -> None:
    """Each endpoint is a plain function (no signature made up for it): the path's
    parameters are typed, documented and reported in the declaration's order."""
    app = create_http_app(VirtualController(), lambda: STATS, actions=(*CONTROL_ACTIONS, SLOT))
    assert not any(hasattr(route, "endpoint") and "__signature__" in vars(route.endpoint)
                   for route in app.routes)  # fmt: skip
    with BlockingClient(app) as client:
        r = client.request("PUT", "/api/slots/3/0.5", json={"y": 1})
        assert r.status_code == 200, r.text
        assert r.json()["alarms"] == [{"code": 8303, "subcode": 0, "text": "x=0.5 y=1.0"}]
        op = client.get("/openapi.json").json()["paths"]["/api/slots/{n}/{x}"]["put"]
        assert [(p["name"], p["schema"]["type"]) for p in op["parameters"]] == [
            ("n", "integer"),
            ("x", "number"),
        ]
        assert op["requestBody"]["required"] is True
        r = client.request("PUT", "/api/slots/x/abc", json={"y": 9})
        assert (r.status_code, r.json()["error"]) == (
            422,
            "PUT /api/slots/x/abc: path.n: Input should be a valid integer, unable to parse "
            "string as an integer; path.x: Input should be a valid number, unable to parse "
            "string as a number; y: must lie in 0..2 m, not 9",
        )
        r = client.request("PUT", "/api/slots/30/5", json={"y": 1})
        assert (r.status_code, r.json()["error"]) == (
            422,
            "PUT /api/slots/30/5: n: must lie in 0..9, not 30",
        )


def test_tcp_speed_zero_is_refused_by_every_surface(
    beacon_api: tuple[BlockingClient, VirtualController],
) -> None:
    """Issue 19's drift: the scenario accepted 0 (an inclusive range) and failed when the
    event fired; the control API and ``fsu.set`` refused it. Now refused everywhere."""
    client, controller = beacon_api
    words = "tcp_speed_mm_s: must be > 0 mm/s, not 0"
    r = client.post("/api/fsu", json={"tcp_speed_mm_s": 0})
    assert (r.status_code, r.json()["error"]) == (422, f"POST /api/fsu: {words}")
    with pytest.raises(ConfigError, match=f"{words}$"):
        parse_scenario({"events": [{"at": 0, "action": "fsu", "tcp_speed_mm_s": 0}]})
    r = client.post("/api/scenario", json={"events": [{"at": 0, "action": "fsu",
                                                       "tcp_speed_mm_s": 0}]})  # fmt: skip
    assert r.status_code == 400
    assert r.json()["error"].endswith(words)
    with pytest.raises(ValueError, match="must be > 0"):
        controller.set_fsu(tcp_speed_mm_s=0.0)


def test_a_rule_between_parameters_has_the_same_words_everywhere(
    beacon_api: tuple[BlockingClient, VirtualController],
) -> None:
    client, _ = beacon_api
    words = "retreat_ms: applies to a clamping only"
    r = client.post("/api/pfl", json={"event": "contact", "retreat_ms": 5})
    assert (r.status_code, r.json()["error"]) == (400, f"POST /api/pfl: {words}")
    event = {"at": 0, "action": "pfl", "event": "contact", "retreat_ms": 5}
    with pytest.raises(ConfigError, match=f"{words}$"):
        parse_scenario({"events": [event]})


def test_a_refusal_that_is_not_ours_is_a_server_error_not_a_client_error() -> None:
    """The control API maps our errors to 4xx, not every ValueError: a bug stays a 500."""

    def broken(target: Any, params: Any) -> None:
        raise KeyError("a bug")

    bug = ActionSpec("bug", "/api/bug", "A broken action.", broken)
    app = create_http_app(VirtualController(), lambda: STATS, actions=(*CONTROL_ACTIONS, bug))
    with BlockingClient(app, raise_server_exceptions=False) as client:
        assert client.post("/api/bug").status_code == 500
        assert client.get("/api/io/20018").status_code == 400  # ours: an unreadable address


# --------------------------------------------------------------------------- Hypothesis

PARAMS: Final = [
    (spec, param)
    for spec in CONTROL_ACTIONS
    if spec.in_scenarios and not spec.path_keys  # a path carries text only: tested above
    for param in spec.params
]


def _valid(param: Param) -> object:
    """A value every surface accepts for ``param``."""
    if param.choices:
        return param.choices[0]
    if param.kind == "bool":
        return True
    if param.kind == "str":
        return "x"
    low = param.ge if param.ge is not None else (param.gt + 1 if param.gt is not None else 0)
    return int(low)


def _values(param: Param) -> st.SearchStrategy[object]:
    """In and out of range, and of the wrong kind, all writable in JSON and in TOML."""
    around: list[float] = [b for b in (param.ge, param.gt, param.le) if b is not None]
    edges = [int(b) + d for b in around for d in (-1, 0, 1)]
    return st.one_of(
        st.sampled_from(edges or [0]),
        st.integers(-(2**40), 2**40),
        st.floats(allow_nan=False, allow_infinity=False),
        st.booleans(),
        st.sampled_from([*param.choices, "contactt", "TEACH", ""]),
        st.text(st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")), max_size=140),
    )


def _toml(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        assert math.isfinite(value)
        return repr(value)
    return json.dumps(value, ensure_ascii=False) if isinstance(value, str) else str(value)


@pytest.fixture(scope="module")
def api() -> Iterator[BlockingClient]:
    app = create_http_app(VirtualController(), lambda: STATS)
    with BlockingClient(app) as client:
        yield client


@pytest.mark.parametrize(("spec", "param"), PARAMS, ids=[f"{s.name}.{p.name}" for s, p in PARAMS])
@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(data=st.data())
def test_a_value_gets_the_same_answer_over_http_and_in_a_scenario_file(
    api: BlockingClient, spec: ActionSpec, param: Param, data: st.DataObject
) -> None:
    value = data.draw(_values(param), label=param.name)
    body = {p.name: _valid(p) for p in spec.params if p.required}
    body[param.name] = value
    # JSON has one kind of number: 40.0 for an integer parameter is 40 over HTTP (as the
    # OpenAPI document's "integer" says), where TOML tells 40.0 (a float) from 40
    in_file = dict(body)
    if param.kind == "int" and isinstance(value, float) and value.is_integer():
        in_file[param.name] = int(value)
    lines = ["[[events]]", "at = 0.0", f'action = "{spec.name}"']
    lines += [f"{k} = {_toml(v)}" for k, v in in_file.items()]
    refused = ""
    try:
        parse_scenario(tomllib.loads("\n".join(lines) + "\n"), source="f.toml")
    except ConfigError as exc:
        refused = str(exc)
    r = api.post(spec.path, content=json.dumps(body), headers={"content-type": "application/json"})
    if refused:
        assert r.status_code in (400, 422), (refused, r.text)
        tail = refused.split(f"events[0] ({spec.name})", 1)[1].lstrip(".:").strip()
        assert r.json()["error"] == f"POST {spec.path}: {tail}"
    else:
        assert r.status_code in (200, 400), r.text  # 400: the controller refuses it now
        if r.status_code == 400:
            assert param.name not in r.json()["error"].split(": ", 2)[1:2]
