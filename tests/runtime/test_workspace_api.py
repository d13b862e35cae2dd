"""Issue 21 item 6 over HTTP: the workspace in ``GET /api/state``, ``POST /api/workspace``
and ``DELETE /api/workspace/NAME`` (declared as actions, served in process)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from pymotoros.controller import VirtualController, cell_from_dict
from pymotoros.runtime.http_api import create_http_app

from .support import STATS
from .test_control_surface import BlockingClient

TABLE = {"name": "table", "box": [1.2, 0.8, 0.05], "xyz": [0.6, 0.0, -0.03]}
ON_THE_ARM = {"name": "crate", "sphere": 0.1, "xyz": [0.0, 0.0, 0.975]}
"""Around the HC10's elbow at its zero pose: touched as soon as it appears."""


@pytest.fixture
def hc10() -> Iterator[tuple[BlockingClient, VirtualController]]:
    controller = VirtualController(cell_from_dict({"robot": {"model": "hc10"}}))
    with BlockingClient(create_http_app(controller, lambda: STATS)) as client:
        yield client, controller


def test_obstacles_are_put_moved_and_removed_by_name(
    hc10: tuple[BlockingClient, VirtualController],
) -> None:
    api, controller = hc10
    assert api.get("/api/state").json()["workspace"] == {"obstacles": [], "contacts": []}
    r = api.post("/api/workspace", json=TABLE)
    assert r.status_code == 200, r.text
    (table,) = r.json()["workspace"]["obstacles"]
    assert (table["name"], table["box"], table["xyz"]) == (
        "table",
        [1.2, 0.8, 0.05],
        [0.6, 0.0, -0.03],
    )
    assert table["rpy_deg"] == [0.0, 0.0, 0.0]
    assert set(table) == {"name", "box", "xyz", "rpy_deg"}  # only the keys it has
    again = api.post("/api/workspace", json=table)  # what the state shows posts back
    assert again.status_code == 200, again.text
    assert again.json()["workspace"]["obstacles"] == [table]
    moved = {**TABLE, "xyz": [0.7, 0.1, -0.03], "rpy_deg": [0, 0, 90]}
    r = api.post("/api/workspace", json=moved)
    (table,) = r.json()["workspace"]["obstacles"]  # the same one, moved: not a second
    assert table["xyz"] == [0.7, 0.1, -0.03]
    assert table["rpy_deg"] == pytest.approx([0.0, 0.0, 90.0])
    api.post(
        "/api/workspace", json={"name": "post", "cylinder": [0.05, 1.5], "xyz": [0.5, -0.4, 0.75]}
    )
    names = [o.name for o in controller.obstacles]
    assert names == ["table", "post"]
    r = api.request("DELETE", "/api/workspace/table")
    assert r.status_code == 200, r.text
    assert [o["name"] for o in r.json()["workspace"]["obstacles"]] == ["post"]
    r = api.request("DELETE", "/api/workspace/table")
    assert r.status_code == 404, r.text
    assert r.json()["error"] == (
        "DELETE /api/workspace/table: no obstacle named 'table'; obstacles: post"
    )
    api.request("DELETE", "/api/workspace/post")
    r = api.request("DELETE", "/api/workspace/post")
    assert (r.status_code, r.json()["error"]) == (
        404,
        "DELETE /api/workspace/post: no obstacle named 'post'; obstacles: none",
    )
    schema = api.get("/openapi.json").json()["paths"]["/api/workspace/{name}"]["delete"]
    assert "404" in schema["responses"]


@pytest.mark.parametrize(
    ("body", "status", "words"),
    [
        ({"name": "t", "box": [1, 1], "xyz": [0, 0, 0]}, 422, "box: must hold 3 numbers, not 2"),
        (
            {"name": "t", "box": [1, -1, 1], "xyz": [0, 0, 0]},
            422,
            "box: [1] must be > 0 and <= 100 m",
        ),
        ({"name": "t", "sphere": "big", "xyz": [0, 0, 0]}, 422, "sphere: must be a number"),
        ({"name": "t", "sphere": 0.1}, 422, "xyz: Field required"),
        ({"name": "t", "xyz": [0, 0, 0]}, 400, "an obstacle has exactly one of box, cylinder"),
        (
            {"name": "t", "sphere": 1, "box": [1, 1, 1], "xyz": [0, 0, 0]},
            400,
            "gives box and sphere",
        ),
        ({"name": "t", "sphere": 1, "xyz": [0, 0, 0], "frame": "R9"}, 400, "obstacle.frame:"),
        ({"name": "a/b", "sphere": 1, "xyz": [0, 0, 0]}, 422, "name: must be a non-empty name"),
        ({"name": "t", "cone": 1, "xyz": [0, 0, 0]}, 422, "unknown field 'cone'"),
    ],
)
def test_a_bad_obstacle_is_a_4xx_naming_the_key(
    hc10: tuple[BlockingClient, VirtualController], body: dict[str, object], status: int, words: str
) -> None:
    api, controller = hc10
    r = api.post("/api/workspace", json=body)
    assert r.status_code == status, r.text
    assert r.json()["error"].startswith("POST /api/workspace: ")
    assert words in r.json()["error"]
    assert controller.obstacles == ()


def test_a_contact_names_the_obstacle_and_the_link(
    hc10: tuple[BlockingClient, VirtualController],
) -> None:
    api, controller = hc10
    api.post("/api/workspace", json=ON_THE_ARM)
    for _ in range(3):
        controller.tick()
    contacts = api.get("/api/state").json()["workspace"]["contacts"]
    assert contacts, "the crate sits on the elbow"
    assert {c["obstacle"] for c in contacts} == {"crate"}
    assert all(c["link"].startswith("link_") and c["group"] == "R1" for c in contacts)
    assert all(c["depth_mm"] > 0 for c in contacts)
    api.request("DELETE", "/api/workspace/crate")
    controller.tick()
    assert api.get("/api/state").json()["workspace"] == {"obstacles": [], "contacts": []}


def test_the_endpoints_are_in_the_schema_and_the_pendant_list(
    hc10: tuple[BlockingClient, VirtualController],
) -> None:
    api, _ = hc10
    paths = api.get("/openapi.json").json()["paths"]
    assert "post" in paths["/api/workspace"]
    assert "delete" in paths["/api/workspace/{name}"]
    state = api.get("/openapi.json").json()["components"]["schemas"]
    assert "workspace" in state["StateModel"]["properties"]
    listed = {a["name"]: a for a in api.get("/api/pendant/actions").json()}
    assert listed["remove_obstacle"]["method"] == "DELETE"
    assert listed["obstacle"]["path"] == "/api/workspace"
