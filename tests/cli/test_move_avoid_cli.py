"""``pymotoros move J1 ... Jn --config CELL --avoid``: the joint move planned around the
cell's obstacles (issue 21 item 4), against ``pymotoros sim --config`` with the same
cell, whose twin stops the HC10 (PFL) at any contact."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_REFUSED, EXIT_USAGE

LEFT = ("-0.8", "0.6", "0", "0", "0", "0")
RIGHT = ("0.8", "0.6", "0", "0", "0", "0")
"""Swinging S from LEFT to RIGHT with L tilted forward: the upper arm meets the ball."""
INSIDE = ("0", "1.0", "0", "0", "0", "0")
CELL = f"""
[robot]
model = "hc10"
[initial.joints]
R1 = [{", ".join(LEFT)}]
[[workspace.obstacles]]
name = "ball"
sphere = 0.1
xyz = [0.45, 0.0, 0.75]
"""


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("avoid") / "cell.toml"
    path.write_text(CELL, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def sim(cell: Path) -> Iterator[Sim]:
    with running_sim("--config", str(cell)) as s:
        yield s


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


def test_move_avoid_reaches_the_goal_without_contact(sim: Sim, cell: Path) -> None:
    assert invoke(sim, "enable").exit_code == 0
    plain = invoke(sim, "move", *RIGHT, "--config", str(cell))
    assert plain.exit_code == EXIT_REFUSED, plain.output  # the straight swing hits the ball
    assert "touches obstacle 'ball'" in plain.stderr
    result = invoke(sim, "move", *RIGHT, "--config", str(cell), "--avoid", "--json")
    assert result.exit_code == 0, result.output
    positions = json.loads(result.stdout)["positions"]
    assert positions == pytest.approx([float(v) for v in RIGHT], abs=1e-3)
    state = sim.api("/api/state")
    assert state["workspace"]["contacts"] == []
    assert state["alarms"] == []
    assert state["pfl"] == "idle"  # a touch on the way would have stopped it (5011)


def test_a_blocked_goal_is_one_line_and_exit_1(sim: Sim, cell: Path) -> None:
    result = invoke(sim, "move", *INSIDE, "--config", str(cell), "--avoid")
    assert result.exit_code == EXIT_REFUSED
    assert result.stderr == (
        "error: not started: the goal is in collision: obstacle 'ball' (R1 link_2_l touches it)\n"
    )
    assert result.stdout == ""


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        ((), "--avoid needs --config CELL.toml whose [workspace] has obstacles"),
        (("--pose", "--linear", "--config", "CELL"), "a straight line (--linear, --relative)"),
    ],
)
def test_avoid_usage_errors(sim: Sim, cell: Path, extra: tuple[str, ...], words: str) -> None:
    args = [a if a != "CELL" else str(cell) for a in extra]
    result = invoke(sim, "move", *RIGHT, "--avoid", *args)
    assert result.exit_code == EXIT_USAGE, result.output
    assert words in result.stderr
