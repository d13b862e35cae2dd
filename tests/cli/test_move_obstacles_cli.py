"""``pymotoros move --config CELL`` with obstacles: a joint move that would hit one is
refused before anything moves (exit 1, the obstacle named), unless ``--force``; a clear
move goes. Against ``pymotoros sim`` (which knows nothing of the cell's obstacles, as a
real controller would not)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_REFUSED

from .test_workspace_cli import CELL

INTO_THE_BALL = ("0", "1.0", "0", "0", "0", "0")
"""Tilting L forward from the zero pose: the upper arm meets the ball (test_workspace_cli)."""
CLEAR = ("1.0", "0", "0", "0", "0", "0")


sim = sim_fixture("--robot", "hc10")


@pytest.fixture
def cell(tmp_path: Path) -> Path:
    path = tmp_path / "cell.toml"
    path.write_text(CELL)
    return path


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


def _positions(sim: Sim) -> list[float]:
    return [float(v) for v in sim.api("/api/state")["groups"][0]["feedback_rad"]]


def test_move_refuses_a_colliding_move_unless_forced(sim: Sim, cell: Path) -> None:
    assert invoke(sim, "enable").exit_code == 0
    before = _positions(sim)
    refused = invoke(sim, "move", *INTO_THE_BALL, "--config", str(cell))
    assert refused.exit_code == EXIT_REFUSED, refused.output
    assert "not started" in refused.stderr
    assert "link_2_l touches obstacle 'ball'" in refused.stderr
    assert "--force" in refused.stderr
    assert _positions(sim) == before  # nothing was sent

    clear = invoke(sim, "move", *CLEAR, "--config", str(cell), "--json")
    assert clear.exit_code == 0, clear.output
    assert json.loads(clear.stdout)["positions"][0] == pytest.approx(1.0, abs=1e-3)

    back = invoke(sim, "move", "0", "0", "0", "0", "0", "0", "--config", str(cell))
    assert back.exit_code == 0, back.output
    forced = invoke(sim, "move", *INTO_THE_BALL, "--config", str(cell), "--force", "--json")
    assert forced.exit_code == 0, forced.output  # the twin knows no ball: it moves
    assert json.loads(forced.stdout)["positions"][1] == pytest.approx(1.0, abs=1e-3)


def test_move_without_the_cell_is_not_checked(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    result = invoke(sim, "move", "0", "0", "0", "0", "0", "0")
    assert result.exit_code == 0, result.output
