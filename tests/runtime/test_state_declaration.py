"""The state document is declared once, by the snapshot: a field added to it (or to a part
of it) appears in ``GET /api/state``, its OpenAPI schema and the pendant's feed with no
other edit."""

from __future__ import annotations

import dataclasses
from collections.abc import AsyncIterator
from dataclasses import dataclass, field
from typing import Any, Literal

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.api import (
    INLINE,
    OMIT,
    ControllerSnapshot,
    OperatorSnapshot,
    described,
)
from pymotoros.controller.safety import SafetySnapshot
from pymotoros.runtime.http_api import StateModel, create_http_app
from pymotoros.runtime.snapshot_document import document_encoder, document_model, field_docs

from .support import STATS


@dataclass(frozen=True, slots=True)
class DoorState:
    """A toy safety function's state, declared only here."""

    open: bool = field(default=False, metadata=described("The cell door is open."))
    opened: int = field(default=0, metadata=described("How many times it was opened since boot."))


@dataclass(frozen=True, slots=True)
class Lights:
    """A toy part whose fields join the document's top level."""

    beacon: Literal["green", "amber", "red"] = field(
        default="green", metadata=described("The cell's beacon colour.")
    )


@dataclass(frozen=True, slots=True)
class DoorSnapshot(ControllerSnapshot):
    door: DoorState = field(default=DoorState(), metadata=described("The cell door's interlock."))
    lights: Lights = field(default=Lights("amber"), metadata=INLINE)
    secret: int = field(default=7, metadata=OMIT)


class DoorController(VirtualController):
    """The real controller, its snapshot extended by the toy declaration."""

    def snapshot(self) -> ControllerSnapshot:
        base = super().snapshot()
        values = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)}
        return DoorSnapshot(**values, door=DoorState(open=True, opened=2))


@pytest.fixture
async def door_api() -> AsyncIterator[httpx.AsyncClient]:
    app = create_http_app(DoorController(), lambda: STATS)
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://sim") as client:
        yield client


async def test_a_field_declared_in_the_snapshot_is_in_the_state_and_its_schema(
    door_api: httpx.AsyncClient,
) -> None:
    doc = (await door_api.get("/api/state")).json()
    assert doc["door"] == {"open": True, "opened": 2}
    assert doc["beacon"] == "amber"  # an inline part: its fields at the top level
    assert "lights" not in doc
    assert "secret" not in doc
    assert doc["pfl"] == "idle"  # the rest unchanged (the default cell has PFL)
    answer = (await door_api.post("/api/hold", json={"on": True})).json()
    assert answer["door"] == {"open": True, "opened": 2}  # every answer is the same document

    schema = (await door_api.get("/openapi.json")).json()
    defs = schema["components"]["schemas"]
    state_ref = schema["paths"]["/api/state"]["get"]["responses"]["200"]["content"]
    state = defs[state_ref["application/json"]["schema"]["$ref"].rsplit("/", 1)[1]]
    door = state["properties"]["door"]
    assert door["description"] == "The cell door's interlock."
    door_schema = defs[door["$ref"].rsplit("/", 1)[1]] if "$ref" in door else door
    assert door_schema["properties"]["open"]["description"] == "The cell door is open."
    assert door_schema["properties"]["opened"]["type"] == "integer"
    assert state["properties"]["beacon"]["enum"] == ["green", "amber", "red"]
    assert state["properties"]["beacon"]["description"] == "The cell's beacon colour."
    assert "secret" not in state["properties"]
    assert {"tick", "ports", "fsu", "pfl"} <= set(state["properties"])


async def test_the_pendant_feed_carries_the_declared_field() -> None:
    app = create_http_app(DoorController(), lambda: STATS)
    doc = app.state.pendant_feed.document()
    assert doc["door"] == {"open": True, "opened": 2}
    assert doc["beacon"] == "amber"


def test_the_plain_snapshots_schema_is_unchanged_by_the_toy() -> None:
    assert "door" not in StateModel.model_fields
    assert {"fsu", "pfl", "events", "motoros", "tick", "ports"} <= set(StateModel.model_fields)


def test_the_safety_units_part_shows_each_function_at_the_top_level() -> None:
    """fsu and pfl are the safety unit's fields (its own part of the snapshot), inlined
    where the document has always had them."""
    names = [f.name for f in dataclasses.fields(SafetySnapshot)]
    doc = document_encoder(ControllerSnapshot)(VirtualController().snapshot())
    assert set(names) <= set(doc)
    assert "safety" not in doc
    assert field_docs(SafetySnapshot)["fsu"].startswith("The FSU speed limits")


def test_a_type_the_document_cannot_encode_is_refused_when_the_encoder_is_built() -> None:
    @dataclass(frozen=True)
    class Odd(ControllerSnapshot):
        weird: complex | str = 0j

    with pytest.raises(TypeError, match="union"):
        document_encoder(Odd)


def _keys(doc: dict[str, Any]) -> list[str]:
    return list(doc)


def test_the_documents_keys_keep_their_place() -> None:
    """The contract's keys, in the order GET /api/state always had (``tick`` excepted: the
    runtime's additions come last)."""
    doc = document_encoder(ControllerSnapshot)(VirtualController().snapshot())
    assert _keys(doc) == [
        "mode", "remote", "servo", "estop", "hold", "alarms", "motion_ready", "groups",
        "fsu", "pfl", "events", "motoros", "workspace",
    ]  # fmt: skip


def test_a_description_is_data_so_a_type_without_source_keeps_it() -> None:
    """A field's description is its metadata, not a docstring read back from a source
    file: a part built at run time (no source to read) is described in the schema."""
    level = field(default=3, metadata=described("The tank's level (%)."))
    tank = dataclasses.make_dataclass("Tank", [("level", int, level)], frozen=True)
    schema = document_model(tank).model_json_schema()
    assert schema["properties"]["level"]["description"] == "The tank's level (%)."
    assert document_encoder(tank)(tank()) == {"level": 3}


def test_the_operator_keys_part_shows_each_key_at_the_top_level() -> None:
    """mode … alarms are the pendant's keys' fields (their own part of the snapshot, filled
    by ``OperatorKeys.snapshot``), inlined where the document has always had them; the
    pendant's extras of the part (errors, eco) stay out of the document."""
    vc = VirtualController()
    vc.set_hold(True)
    shown = [f.name for f in dataclasses.fields(OperatorSnapshot) if f.metadata != OMIT]
    doc = document_encoder(ControllerSnapshot)(vc.snapshot())
    assert (
        list(doc)[: len(shown)] == shown == ["mode", "remote", "servo", "estop", "hold", "alarms"]
    )
    assert doc["hold"] is True
    assert not {"operator", "errors", "eco"} & set(doc)
    assert StateModel.model_fields["hold"].description == field_docs(OperatorSnapshot)["hold"]
