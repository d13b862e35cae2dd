"""``pymotoros move --pose/--linear/--relative --config CELL`` against ``pymotoros sim
--config CELL`` (issue 29 item 3): a Cartesian move into the fixture is refused before
anything moves, as a joint move is; ``--force`` sends it (PFL 5011 stops the arm) and
the error says where the robot stands, with units and the contact; a robot touching
the fixture may back out and nothing else; ``--avoid`` takes a pose goal."""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_REFUSED

CELL = str(Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_table_fixture.toml")
INTO = ("0.70", "0.0", "-0.10", "180", "0", "0")
"""The issue's pose: the gripper 75 mm into the fixture (base coordinates, deg)."""
ABOVE = ("0.70", "0.0", "0.10", "180", "0", "0")
PFL_WAIT_S = 10.0
"""Bound on the wait for the PFL stop (500 ms on the sim's clock) to let `enable` through."""
POLL_S = 0.05


@pytest.fixture
def sim() -> Iterator[Sim]:
    with running_sim("--config", CELL) as s:
        yield s


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


def move(sim: Sim, *args: str) -> Result:
    return invoke(sim, "move", *args, "--tool", "0", "--config", CELL)


def _enable_after_pfl(sim: Sim) -> bool:
    """``enable`` until it is accepted (the PFL stop still holds at first), bounded."""
    deadline = time.monotonic() + PFL_WAIT_S
    while time.monotonic() < deadline:
        if invoke(sim, "enable").exit_code == 0:
            return True
        time.sleep(POLL_S)
    return False


def _positions(sim: Sim) -> list[float]:
    return [float(v) for v in sim.api("/api/state")["groups"][0]["feedback_rad"]]


def test_a_cartesian_move_into_the_fixture_is_refused_unless_forced(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    before = _positions(sim)
    refused = move(sim, "--pose", *INTO, "--deg")  # the command
    assert refused.exit_code == EXIT_REFUSED, refused.output
    assert "R1 tool touches obstacle 'fixture' (" in refused.stderr
    assert _positions(sim) == before
    assert move(sim, "--pose", *ABOVE, "--deg").exit_code == 0  # clear: it goes
    before = _positions(sim)
    for how in (("--pose", *INTO, "--deg", "--linear"), ("--relative", "dz=-0.2")):
        refused = move(sim, *how)
        assert refused.exit_code == EXIT_REFUSED, refused.output
        assert "error: not started: the planned move would hit: collision at " in refused.stderr
        assert "R1 tool touches obstacle 'fixture' (" in refused.stderr
        assert "--force" in refused.stderr
        assert _positions(sim) == before  # nothing was sent
        assert sim.api("/api/state")["pfl"] == "idle"


def test_a_forced_contact_says_where_the_robot_stands_and_backs_out(sim: Sim) -> None:
    """The issue's ``--force`` run: PFL 5011 at the fixture; the error said "the robot
    stands; position unknown" although the position was known."""
    assert invoke(sim, "enable").exit_code == 0
    forced = move(sim, "--pose", *INTO, "--deg", "--force")
    assert forced.exit_code == EXIT_REFUSED, forced.output
    assert "PFL_ACTIVE (5011)" in forced.stderr
    assert "where it stopped, R1 tool touches obstacle 'fixture' (" in forced.stderr
    assert "position unknown" not in forced.stderr
    assert forced.stderr.count("stands at [") == 1, forced.stderr  # said once
    assert "the robot was stopped (STOP_MOTION) and stands at [" in forced.stderr
    assert "] deg, TCP x " in forced.stderr  # the CLI adds the --deg values and the TCP
    assert forced.stderr.rstrip().endswith(" mm in base"), forced.stderr

    # touching the fixture: deeper is refused with the way out, out is allowed
    here = _positions(sim)
    deeper = move(sim, "--relative", "dz=-0.01")
    assert deeper.exit_code == EXIT_REFUSED, deeper.output
    assert "the robot starts touching obstacle 'fixture' (R1 tool)" in deeper.stderr
    hint = re.search(
        r"back out first, e\.g\. d[xyz] [+-]0\.020 m "
        r"\(`pymotoros move --relative (d[xyz]=-?0\.020) --tool (0)` with this cell's --config",
        deeper.stderr,
    )
    assert hint is not None, deeper.stderr
    assert _positions(sim) == here
    # the PFL stop holds 500 ms; START_TRAJ_MODE clears it after that
    assert _enable_after_pfl(sim), sim.api("/api/state")["pfl"]
    assert hint.group(2) == "0"  # the tool the check mounted: the step runs guarded
    out = move(sim, "--relative", hint.group(1))
    assert out.exit_code == 0, out.output
    # a plain note line for the person, not a timestamped log record
    notes = [ln for ln in out.stderr.splitlines() if "only takes it away" in ln]
    assert notes == [
        "note: the robot starts touching obstacle 'fixture' (R1 tool); this move only "
        "takes it away (the clearance grows all along the move), so it is allowed"
    ], out.stderr


def test_avoid_takes_a_pose_goal(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    blocked = move(sim, "--pose", *INTO, "--deg", "--avoid")
    assert blocked.exit_code == EXIT_REFUSED, blocked.output
    assert blocked.stderr.endswith(
        "error: not started: the goal is in collision: obstacle 'fixture' (R1 tool touches it)\n"
    )
    clear = move(sim, "--pose", *ABOVE, "--deg", "--avoid", "--json")
    assert clear.exit_code == 0, clear.output
    assert sim.api("/api/state")["workspace"]["contacts"] == []
