"""A JSON body naming a key twice is refused by the control API (issue 13: nothing
silently accepted), and every other body is served as before."""

from __future__ import annotations

import json

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.runtime.body_limit import MAX_BODY_BYTES, MAX_JSON_DEPTH
from pymotoros.runtime.strict_json import DuplicateKeyError, loads_strict

JSON = {"content-type": "application/json"}


# ------------------------------------------------------------------ the parser


@pytest.mark.parametrize(
    ("text", "key", "where"),
    [
        ('{"value": 1, "value": 0}', "value", "the body"),
        ('{"a": {"b": 1, "c": 2, "b": 3}}', "b", "the object at a"),
        ('{"events": [{"at": 0}, {"at": 1, "at": 2}]}', "at", "the object at events[1]"),
        ('[[{"x": 1}], [{"y": 1, "y": 1}]]', "y", "the object at [1][0]"),
        ('{"": 1, "": 2}', "", "the body"),
        ('{"\\u0061": 1, "a": 2}', "a", "the body"),  # the same key, spelt two ways
    ],
)
def test_a_repeated_key_is_found_at_any_depth(text: str, key: str, where: str) -> None:
    with pytest.raises(DuplicateKeyError) as info:
        loads_strict(text)
    assert (info.value.key, info.value.where) == (key, where)
    assert repr(key) in str(info.value)


@pytest.mark.parametrize(
    "text",
    ['{"a": 1, "b": {"a": 2}}', '[{"a": 1}, {"a": 2}]', "[]", "3", '"x"', '{"a": [1, 1]}'],
)
def test_equal_keys_in_different_objects_are_fine(text: str) -> None:
    assert loads_strict(text) == json.loads(text)


def test_invalid_json_is_the_parsers_usual_error() -> None:
    with pytest.raises(json.JSONDecodeError):
        loads_strict(b"{not json")


# ------------------------------------------------------------------ the control API


async def test_a_repeated_top_level_key_is_422_and_changes_nothing(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    r = await api.post(
        "/api/io", content=b'{"address": 20010, "value": 1, "value": 0}', headers=JSON
    )
    assert r.status_code == 422
    assert list(r.json()) == ["error"]
    error = r.json()["error"]
    assert error.startswith("POST /api/io: the key 'value' is given more than once in the body")
    assert "send each key once" in error
    assert controller.read_io_bit(20010).value == 0


async def test_a_repeated_nested_key_is_422(api: httpx.AsyncClient) -> None:
    body = b'{"events": [{"at": 0.0, "action": "hold", "on": true, "on": false}]}'
    r = await api.post("/api/scenario", content=body, headers=JSON)
    assert r.status_code == 422
    assert "the key 'on' is given more than once in the object at events[0]" in r.json()["error"]


async def test_the_pendants_endpoint_is_covered_too(api: httpx.AsyncClient) -> None:
    body = b'{"name": "a.toml", "toml": "", "name": "b.toml"}'
    r = await api.post("/api/pendant/scenario", content=body, headers=JSON)
    assert r.status_code == 422
    assert "'name'" in r.json()["error"]


async def test_the_error_has_the_shape_of_the_apis_other_malformed_body_errors(
    api: httpx.AsyncClient,
) -> None:
    invalid = await api.post("/api/hold", content=b"{not json", headers=JSON)
    repeated = await api.post("/api/hold", content=b'{"on": true, "on": true}', headers=JSON)
    assert invalid.status_code == repeated.status_code == 422
    assert invalid.headers["content-type"] == repeated.headers["content-type"]
    assert set(invalid.json()) == set(repeated.json()) == {"error"}
    assert repeated.json()["error"].startswith("POST /api/hold: ")


async def test_normal_bodies_are_served_as_before(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    r = await api.post("/api/io", json={"address": 20010, "value": 1})
    assert r.status_code == 200
    assert controller.read_io_bit(20010).value == 1
    assert (await api.post("/api/hold", json={"on": True})).json()["hold"] is True
    r = await api.post(
        "/api/scenario", json={"events": [{"at": 0.0, "action": "hold", "on": True}]}
    )
    assert r.status_code == 200
    assert (await api.post("/api/reset")).status_code == 200  # no body at all
    r = await api.post("/api/hold", content=b"{not json", headers=JSON)  # still FastAPI's
    assert r.status_code == 422
    assert "not valid JSON" in r.json()["error"]
    r = await api.post("/api/hold", json={"on": True, "extra": 1})  # still refused by name
    assert r.status_code == 422
    assert "unknown field 'extra'" in r.json()["error"]


async def test_the_body_limits_still_apply_first(api: httpx.AsyncClient) -> None:
    deep = b"[" * (MAX_JSON_DEPTH + 1) + b"]" * (MAX_JSON_DEPTH + 1)
    r = await api.post("/api/hold", content=deep, headers=JSON)
    assert r.status_code == 400
    assert "nests deeper" in r.json()["error"]
    big = b'{"on": true, "pad": "' + b"x" * MAX_BODY_BYTES + b'", "on": true}'
    r = await api.post("/api/hold", content=big, headers=JSON)
    assert r.status_code == 413


async def test_a_body_is_parsed_once(
    api: httpx.AsyncClient, controller: VirtualController, monkeypatch: pytest.MonkeyPatch
) -> None:
    """FastAPI takes the body as the duplicate check parsed it (Starlette's own parse in
    ``Request.json()`` is never reached), and an IO write with it still takes effect."""

    class NoSecondParse:
        @staticmethod
        def loads(*args: object, **kwargs: object) -> object:
            raise AssertionError("the body was parsed a second time")

    monkeypatch.setattr("starlette.requests.json", NoSecondParse)
    r = await api.post("/api/io", json={"address": 20010, "value": 1})
    assert r.status_code == 200
    assert controller.read_io_bit(20010).value == 1
