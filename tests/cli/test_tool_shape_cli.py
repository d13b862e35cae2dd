"""The tool's collision shape (``shape`` in a ``[[tools]]`` entry) in ``check`` and
``plan --avoid``, and in the twin's contact check: the three mount it in one place
(:meth:`pymotoros.kinematics.collision.GroupBody.set_tool`)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from pymotoros.cli.main import cli
from pymotoros.controller.cell import cell_from_dict, load_cell
from pymotoros.errors import ConfigError
from pymotoros.kinematics.collision import world_for_cell
from pymotoros.models.cell import cell_models_from_dict, load_cell_models
from pymotoros.models.workspace import Capsule, ToolShape
from pymotoros.trajectory.check import EXIT_OK, EXIT_REFUSED

START = "0,-1.0,1.0,0,0,0"
"""The HC10 leaning back, its wrist straight."""
REACH_DOWN = "0,-1.0,1.0,0,-2.0,0"
"""From START, B turns the flange down: 0.73 m up, 0.13 m behind axis S."""
CELL = """
[robot]
model = "hc10"

[[tools]]
number = 0
name = "spindle"
tcp_m = [0.0, 0.0, 0.2]
shape = {capsule = [0.02, 0.2]}   # 0.2 m out of the flange, 40 mm thick

[[tools]]
number = 1
name = "bare flange"

[[workspace.obstacles]]
name = "fixture"
box = [0.2, 0.2, 0.05]
xyz = [-0.13, 0.16, 0.606]        # its top 0.1 m below the flange at REACH_DOWN
"""


def invoke(*args: str) -> Result:
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


@pytest.fixture
def cell(tmp_path: Path) -> Path:
    path = tmp_path / "cell.toml"
    path.write_text(CELL, encoding="utf-8")
    return path


def _traj(tmp_path: Path, cell: Path) -> Path:
    way = tmp_path / "way.csv"
    way.write_text(f"{START}\n{REACH_DOWN}\n", encoding="utf-8")
    out = tmp_path / "traj.csv"
    result = invoke("plan", str(way), "--config", str(cell), "-o", str(out))
    assert result.exit_code == 0, result.output
    return out


def test_check_refuses_the_tool_hitting_the_fixture_and_passes_without_it(
    tmp_path: Path, cell: Path
) -> None:
    traj = _traj(tmp_path, cell)
    with_tool = invoke("check", str(traj), "--config", str(cell), "--json")
    assert with_tool.exit_code == EXIT_REFUSED, with_tool.output
    hits = json.loads(with_tool.stdout)["collisions"]
    assert [(c["obstacle"], c["link"]) for c in hits] == [("fixture", "tool")]
    assert hits[0]["depth_mm"] > 50  # the spindle goes 0.12 m into it
    text = invoke("check", str(traj), "--config", str(cell))
    assert "R1 tool touches obstacle 'fixture'" in text.output
    # the flange itself clears the fixture: with the bare flange (tool 1) it passes
    bare = invoke("check", str(traj), "--config", str(cell), "--tool", "1", "--json")
    assert bare.exit_code == EXIT_OK, bare.output
    assert json.loads(bare.stdout)["collisions"] == []


def test_the_cells_initial_tool_is_the_default(tmp_path: Path, cell: Path) -> None:
    traj = _traj(tmp_path, cell)
    booted = tmp_path / "booted.toml"
    booted.write_text(CELL + "\n[initial.tool]\nR1 = 1\n", encoding="utf-8")
    assert load_cell_models(booted).default_tool(0) == 1
    assert invoke("check", str(traj), "--config", str(booted)).exit_code == EXIT_OK
    refused = invoke("check", str(traj), "--config", str(booted), "--tool", "0")
    assert refused.exit_code == EXIT_REFUSED


def test_plan_avoid_keeps_the_tool_out_of_the_fixture(tmp_path: Path, cell: Path) -> None:
    way = tmp_path / "way.csv"
    way.write_text(f"{START}\n{REACH_DOWN}\n", encoding="utf-8")
    out = tmp_path / "out.csv"
    result = invoke("plan", str(way), "--config", str(cell), "--avoid", "-o", str(out))
    # the goal itself puts the spindle into the fixture: refused, naming the tool
    assert result.exit_code == EXIT_REFUSED
    assert result.stderr.strip() == (
        "refused: waypoint 1 is in collision: obstacle 'fixture' (R1 tool touches it)"
    )
    bare = invoke("plan", str(way), "--config", str(cell), "--avoid", "--tool", "1", "-o", str(out))
    assert bare.exit_code == 0, bare.output


def test_the_shape_is_read_alike_by_the_client_and_the_simulator(cell: Path) -> None:
    expected = ToolShape(Capsule(0.02, 0.2))
    client_side = load_cell_models(cell).tools[0][0]
    assert client_side.shape is not None
    assert client_side.shape.shape == expected.shape
    assert client_side.shape.pose.xyz == (0.0, 0.0, 0.1)  # standing on the flange
    sim_side = load_cell(cell).tool(0, 0)
    assert sim_side.cell_tool == client_side


@pytest.mark.parametrize(
    ("shape", "words"),
    [
        ("{capsule = [0.02]}", "tools[0].shape.capsule: must be [radius, length] in metres"),
        ("{cone = 1}", "tools[0].shape.cone: unknown key (misspelt?); known: box, capsule"),
        ("{sphere = 0.1, box = [1, 1, 1]}", "tools[0].shape: a tool shape has exactly one of"),
        ('"big"', "tools[0].shape: must be a table such as {capsule = [0.03, 0.2]}"),
        ("{box = [0.1, 0.1, 0.1], xyz = [0, 0]}", "tools[0].shape.xyz: must be three numbers"),
    ],
)
def test_a_bad_shape_is_a_config_error_naming_the_key(
    tmp_path: Path, shape: str, words: str
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(
        f'[robot]\nmodel = "hc10"\n[[tools]]\nnumber = 0\nshape = {shape}\n', encoding="utf-8"
    )
    with pytest.raises(ConfigError, match=r"bad\.toml: tools\[0\]\.shape") as client_error:
        load_cell_models(path)
    assert words in str(client_error.value)
    with pytest.raises(ConfigError) as sim_error:
        load_cell(path)
    assert words in str(sim_error.value)


async def test_the_twin_feels_the_tool_too() -> None:
    """The twin mounts the selected tool's shape as ``check`` does: the spindle stops
    the HC10 (PFL) before the flange gets near the fixture."""
    import tomllib

    from pymotoros.client import NotReadyError
    from pymotoros.protocol.constants import NotReadySubcode
    from pymotoros.testing import twin

    data = tomllib.loads(CELL) | {
        "initial": {"joints": {"R1": [float(v) for v in START.split(",")]}}
    }
    goal = [float(v) for v in REACH_DOWN.split(",")]
    async with twin(cell=cell_from_dict(data)) as (robot, the_twin):
        await robot.enable()
        with pytest.raises(NotReadyError) as info:
            await robot.move_joints(goal, speed_scale=0.5)
        assert info.value.reason is NotReadySubcode.PFL_ACTIVE
        touched = the_twin.controller.workspace_contacts
        assert [(c.obstacle, c.link) for c in touched] == [("fixture", "tool")]
    models = cell_models_from_dict(data)
    assert world_for_cell(models, [1]).contacts([goal]) == []  # the bare flange clears it
