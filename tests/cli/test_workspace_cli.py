"""``pymotoros check TRAJ --config CELL`` with obstacles: every collision, exit 1."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner, Result

from pymotoros.cli.main import cli
from pymotoros.trajectory.check import EXIT_OK, EXIT_REFUSED

EXAMPLE_CELL = (
    Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_table_fixture.toml"
)

CELL = """
[robot]
model = "hc10"
[[workspace.obstacles]]
name = "ball"
sphere = 0.1
xyz = [0.45, 0.0, 0.75]
"""


def invoke(*args: str) -> Result:
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def _plan(tmp_path: Path, cell: Path, *rows: str) -> Path:
    way = tmp_path / "way.csv"
    way.write_text("\n".join(rows) + "\n")
    out = tmp_path / "traj.csv"
    result = invoke("plan", str(way), "--config", str(cell), "-o", str(out))
    assert result.exit_code == 0, result.output
    return out


def test_check_reports_the_obstacle_the_link_and_the_time(tmp_path: Path) -> None:
    cell = tmp_path / "cell.toml"
    cell.write_text(CELL)
    traj = _plan(tmp_path, cell, "0,0,0,0,0,0", "0,1.0,0,0,0,0")
    result = invoke("check", str(traj), "--config", str(cell), "--json")
    assert result.exit_code == EXIT_REFUSED
    report = json.loads(result.stdout)
    assert report["accepted"] is True  # MotoROS takes it; the robot would crash
    first = report["collisions"][0]
    assert (first["obstacle"], first["link"]) == ("ball", "link_2_l")
    assert 0 < first["time_s"] < report["duration_s"]
    text = invoke("check", str(traj), "--config", str(cell))
    assert text.exit_code == EXIT_REFUSED
    assert f"collision at {first['time_s']:.3f} s: R1 link_2_l touches obstacle 'ball'" in (
        text.output
    )


def test_a_clear_path_passes_and_json_lists_no_collisions(tmp_path: Path) -> None:
    cell = tmp_path / "cell.toml"
    cell.write_text(CELL)
    traj = _plan(tmp_path, cell, "0,0,0,0,0,0", "1.0,0,0,0,0,0")
    result = invoke("check", str(traj), "--config", str(cell), "--json")
    assert result.exit_code == EXIT_OK, result.output
    assert json.loads(result.stdout)["collisions"] == []


def test_the_example_cell_with_a_table_and_a_fixture(tmp_path: Path) -> None:
    # reaching down in front of the robot: the forearm goes into the fixture
    traj = _plan(tmp_path, EXAMPLE_CELL, "0,0,0,0,0,0", "0,1.4,2.6,0,0,0")
    result = invoke("check", str(traj), "--config", str(EXAMPLE_CELL), "--json")
    assert result.exit_code == EXIT_REFUSED, result.output
    assert "fixture" in {c["obstacle"] for c in json.loads(result.stdout)["collisions"]}


def test_plan_avoid_goes_around_and_passes_the_check(tmp_path: Path) -> None:
    cell = tmp_path / "cell.toml"
    cell.write_text(CELL)
    way = tmp_path / "way.csv"
    way.write_text("-0.8,0.6,0,0,0,0\n0.8,0.6,0,0,0,0\n")
    direct = _plan(tmp_path, cell, "-0.8,0.6,0,0,0,0", "0.8,0.6,0,0,0,0")
    assert invoke("check", str(direct), "--config", str(cell)).exit_code == EXIT_REFUSED
    out = tmp_path / "around.csv"
    result = invoke("plan", str(way), "--config", str(cell), "--avoid", "-o", str(out))
    assert result.exit_code == 0, result.output
    checked = invoke("check", str(out), "--config", str(cell), "--json")
    assert checked.exit_code == EXIT_OK, checked.output
    assert json.loads(checked.stdout)["collisions"] == []


def test_plan_avoid_refuses_a_blocked_goal_in_one_line(tmp_path: Path) -> None:
    cell = tmp_path / "cell.toml"
    cell.write_text(CELL)
    way = tmp_path / "way.csv"
    way.write_text("0,0,0,0,0,0\n0,1.0,0,0,0,0\n")
    result = invoke(
        "plan", str(way), "--config", str(cell), "--avoid", "-o", str(tmp_path / "o.csv")
    )
    assert result.exit_code == EXIT_REFUSED
    assert result.stderr == (
        "refused: waypoint 1 is in collision: obstacle 'ball' (R1 link_2_l touches it)\n"
    )
    assert not (tmp_path / "o.csv").exists()


def test_plan_avoid_needs_a_cell(tmp_path: Path) -> None:
    way = tmp_path / "way.csv"
    way.write_text("0,0,0,0,0,0\n0.1,0,0,0,0,0\n")
    result = invoke("plan", str(way), "--avoid", "-o", str(tmp_path / "o.csv"))
    assert result.exit_code == 2
    assert "--avoid needs --config" in result.output


def test_run_with_the_cell_refuses_a_colliding_trajectory_before_connecting(
    tmp_path: Path,
) -> None:
    cell = tmp_path / "cell.toml"
    cell.write_text(CELL)
    traj = _plan(tmp_path, cell, "0,0,0,0,0,0", "0,1.0,0,0,0,0")
    # no simulator runs: the check stops the command before it connects
    result = invoke("run", str(traj), "--config", str(cell), "--timeout", "0.5")
    assert result.exit_code == EXIT_REFUSED
    assert "collision at" in result.stderr
    assert "not started: fix the trajectory or give --force" in result.stderr
