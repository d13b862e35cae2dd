"""The ``[workspace]`` table of a cell file: obstacles, group placements, every mistake named."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import pytest

from pymotoros.controller.cell import cell_from_dict, load_cell
from pymotoros.errors import ConfigError
from pymotoros.models.cell import cell_models_from_dict, load_cell_models
from pymotoros.models.workspace import (
    DEFAULT_TOOL_RADIUS_M,
    Box,
    Cylinder,
    Obstacle,
    Sphere,
    parse_obstacle,
    workspace_from_dict,
)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_table_fixture.toml"

ISSUE_EXAMPLE = """
[[workspace.obstacles]]
name = "table"
box = [1.2, 0.8, 0.05]
xyz = [0.6, 0.0, -0.03]
rpy_deg = [0, 0, 0]
[[workspace.obstacles]]
name = "post"
cylinder = [0.05, 1.5]
xyz = [0.5, -0.4, 0.75]
[[workspace.obstacles]]
name = "ball"
sphere = 0.1
xyz = [0.4, 0.3, 0.5]
"""


def test_the_issue_example_parses_to_three_shapes() -> None:
    ws = workspace_from_dict(tomllib.loads(ISSUE_EXAMPLE)["workspace"], "cell.toml", ["R1"])
    table, post, ball = ws.obstacles
    assert table == Obstacle("table", Box((1.2, 0.8, 0.05)), table.pose)
    assert table.pose.xyz == (0.6, 0.0, -0.03)
    assert post.shape == Cylinder(0.05, 1.5)
    assert ball.shape == Sphere(0.1)
    assert ws.tool_radius_m == DEFAULT_TOOL_RADIUS_M
    assert ball.as_dict() == {
        "name": "ball",
        "sphere": 0.1,
        "xyz": [0.4, 0.3, 0.5],
        "rpy_deg": [0.0, 0.0, 0.0],
    }


def test_rpy_deg_is_stored_in_radians_and_shown_in_degrees() -> None:
    entry = {"name": "w", "box": [1, 1, 1], "xyz": [0, 0, 0], "rpy_deg": [90, 0, -45]}
    o = parse_obstacle(entry, "k")
    assert o.pose.rpy == pytest.approx((math.pi / 2, 0.0, -math.pi / 4))
    assert o.as_dict()["rpy_deg"] == pytest.approx([90.0, 0.0, -45.0])


BAD: list[tuple[dict[str, Any], str]] = [
    ({"name": "a", "box": [1, 1], "xyz": [0, 0, 0]}, "workspace.obstacles[1].box: must be three"),
    ({"name": "a", "box": [1, -1, 1], "xyz": [0, 0, 0]}, "workspace.obstacles[1].box: "),
    ({"name": "a", "box": [1, 1, True], "xyz": [0, 0, 0]}, "workspace.obstacles[1].box: "),
    ({"name": "a", "cylinder": 0.1, "xyz": [0, 0, 0]}, "workspace.obstacles[1].cylinder: "),
    ({"name": "a", "sphere": 0, "xyz": [0, 0, 0]}, "workspace.obstacles[1].sphere: "),
    ({"name": "a", "sphere": 1000, "xyz": [0, 0, 0]}, "workspace.obstacles[1].sphere: "),
    ({"name": "a", "xyz": [0, 0, 0]}, "workspace.obstacles[1]: an obstacle has exactly one"),
    ({"name": "a", "sphere": 1, "box": [1, 1, 1], "xyz": [0, 0, 0]}, "gives box and sphere"),
    ({"name": "a", "sphere": 1}, "workspace.obstacles[1].xyz: is required"),
    ({"name": "a", "sphere": 1, "xyz": [0, "x", 0]}, "workspace.obstacles[1].xyz: "),
    ({"name": "a", "sphere": 1, "xyz": [0, 0, 0], "rpy_deg": [0, 0]}, "[1].rpy_deg: "),
    ({"name": "", "sphere": 1, "xyz": [0, 0, 0]}, "workspace.obstacles[1].name: "),
    ({"sphere": 1, "xyz": [0, 0, 0]}, "workspace.obstacles[1].name: "),
    ({"name": "a", "sphere": 1, "xyz": [0, 0, 0], "colour": "red"}, "[1].colour: unknown key"),
    ({"name": "a", "sphere": 1, "xyz": [0, 0, 0], "frame": "R9"}, "[1].frame: must name a group"),
    ({"name": "first", "sphere": 1, "xyz": [0, 0, 0]}, "[1].name: 'first' is used twice"),
]


@pytest.mark.parametrize(("entry", "message"), BAD)
def test_every_mistake_is_a_config_error_naming_its_key(
    entry: dict[str, Any], message: str
) -> None:
    table = {"obstacles": [{"name": "first", "sphere": 0.1, "xyz": [2, 2, 2]}, entry]}
    with pytest.raises(ConfigError, match=r"^cell\.toml: ") as info:
        workspace_from_dict(table, "cell.toml", ["R1"])
    assert message in str(info.value)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ([], "workspace: must be a table"),
        ({"obstacles": {"name": "a"}}, "workspace.obstacles: must be an array"),
        ({"walls": []}, "workspace.walls: unknown key"),
        ({"bases": {"R3": {"xyz": [1, 0, 0]}}}, "workspace.bases.R3: no such group"),
        ({"bases": {"R2": {"xyz": [1, 0, 0], "z": 1}}}, "workspace.bases.R2.z: unknown key"),
        ({"tool_radius_m": 0}, "workspace.tool_radius_m: must be in"),
    ],
)
def test_mistakes_in_the_table_itself(table: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        workspace_from_dict(table, "cell.toml", ["R1", "R2"])


def test_frame_and_bases_place_an_obstacle_in_another_groups_frame() -> None:
    ws = workspace_from_dict(
        {
            "bases": {"R2": {"xyz": [2.0, 0.0, 0.0], "rpy_deg": [0, 0, 180]}},
            "obstacles": [
                {"name": "fixture", "box": [0.2, 0.2, 0.2], "xyz": [0.5, 0, 0.1], "frame": "R2"}
            ],
        },
        "cell.toml",
        ["R1", "R2"],
    )
    assert ws.base("R2").xyz == (2.0, 0.0, 0.0)
    assert ws.base("R1").xyz == (0.0, 0.0, 0.0)
    assert ws.obstacles[0].frame == "R2"
    assert ws.obstacles[0].as_dict()["frame"] == "R2"


def test_add_move_and_remove_by_name() -> None:
    ws = workspace_from_dict(tomllib.loads(ISSUE_EXAMPLE)["workspace"], "c", ["R1"])
    moved = ws.with_obstacle(Obstacle("ball", Sphere(0.2)))
    assert [o.name for o in moved.obstacles] == ["table", "post", "ball"]
    assert moved.obstacle("ball") == Obstacle("ball", Sphere(0.2))
    assert [o.name for o in moved.without("post").obstacles] == ["table", "ball"]
    with pytest.raises(ConfigError, match="no obstacle named 'nope'; obstacles: table, post, ball"):
        ws.without("nope")


def test_both_cell_readers_pass_the_workspace_through() -> None:
    data = {"robot": {"model": "hc10"}, **tomllib.loads(ISSUE_EXAMPLE)}
    sim = cell_from_dict(data, source="cell.toml")
    client = cell_models_from_dict(data, source="cell.toml")
    assert sim.workspace == client.workspace
    assert [o.name for o in sim.workspace.obstacles] == ["table", "post", "ball"]
    assert not cell_from_dict({"robot": {"model": "hc10"}}).workspace.obstacles


def test_the_simulators_reader_names_the_key_with_the_file() -> None:
    data = {"workspace": {"obstacles": [{"name": "a", "box": [1, 1], "xyz": [0, 0, 0]}]}}
    with pytest.raises(ConfigError, match=r"^cell.toml: workspace.obstacles\[0\].box: "):
        cell_from_dict(data, source="cell.toml")


def test_the_example_cell_has_a_table_and_a_fixture() -> None:
    names = [o.name for o in load_cell(EXAMPLE).workspace.obstacles]
    assert "table" in names
    assert "fixture" in names
    assert load_cell_models(EXAMPLE).workspace == load_cell(EXAMPLE).workspace
