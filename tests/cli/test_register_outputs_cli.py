"""``pymotoros mreg outputs``: a cell's S1CxG register outputs decoded on the command line
(issue 29 item 5), checked against the pose the robot was moved to."""

from __future__ import annotations

import json
import math
import re
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_USAGE
from pymotoros.kinematics import chain_for

CELL = Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_register_outputs.toml"
GOAL = (0.3, 0.4, 1.6, 0.1, -0.5, 0.2)
"""Where the test moves the HC10 (rad)."""
ONE_PULSE_DEG = 0.01
"""Feedback is in whole pulses: an HC10 axis's pulse is well under 0.01 deg."""


def invoke(*args: str) -> Result:
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


@pytest.fixture(scope="module")
def moved_sim() -> Iterator[Sim]:
    """The register-output cell on port 0, the arm moved to :data:`GOAL`."""
    with running_sim("--config", str(CELL)) as sim:
        joints = [str(v) for v in GOAL]
        moved = invoke("move", *joints, "--enable", "--config", str(CELL), *sim.cli_args())
        assert moved.exit_code == 0, moved.output
        yield sim


def test_outputs_json_decodes_the_pose_the_robot_stands_at(moved_sim: Sim) -> None:
    result = invoke("mreg", "outputs", "--config", str(CELL), "--json", *moved_sim.cli_args())
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    by = {(o["quantity"], o["source"], o["index"]): o for o in data["outputs"]}
    # each axis position (feedback, 0.0001 deg in two registers): the joints moved to
    for k, rad in enumerate(GOAL):
        out = by[("axis_position", "feedback", k)]
        assert out["unit"] == "deg"
        assert out["raw_unit"] == "0.0001deg"
        assert out["value"] == pytest.approx(math.degrees(rad), abs=ONE_PULSE_DEG)
        assert by[("axis_speed", "feedback", k)]["value"] == 0.0  # at rest
    # TCP position: the controller's tool in force is tool 0 (no tool file: tool0), in base
    x, y, z, rx, ry, rz = chain_for("hc10").pose(list(GOAL), "tool0", "base")
    cart = [by[("cartesian", "feedback", k)] for k in range(6)]
    assert [c["unit"] for c in cart] == ["mm"] * 3 + ["deg"] * 3
    assert [c["value"] for c in cart[:3]] == pytest.approx([x * 1e3, y * 1e3, z * 1e3], abs=0.05)
    assert [c["value"] for c in cart[3:]] == pytest.approx(
        [math.degrees(a) for a in (rx, ry, rz)], abs=0.01
    )
    assert by[("tcp_speed", "feedback", 0)]["unit"] == "mm/s"
    assert by[("tcp_speed", "command", 0)]["value"] == 0.0
    assert data["frame"] == {"name": "base", "above_base_link_m": 0.275}
    # the raw words are those `mreg read` shows: M060/M061 hold S in 0.0001 deg
    low, high = data["registers"]["M060"], data["registers"]["M061"]
    assert low | (high << 16) == by[("axis_position", "feedback", 0)]["raw"]
    single = invoke("mreg", "read", "60", *moved_sim.cli_args())
    assert single.stdout.strip() == str(low)


def test_outputs_human_report_names_units_and_frame(moved_sim: Sim) -> None:
    result = invoke("mreg", "outputs", "--config", str(CELL), *moved_sim.cli_args())
    assert result.exit_code == 0, result.output
    text = result.stdout
    assert "0.275 m above base_link (the S-axis height)" in text
    lines = {line.split("  ")[1].strip(): line for line in text.splitlines()[2:-1]}
    assert f"{math.degrees(GOAL[1]):.1f}"[:4] in lines["L position (feedback)"]
    assert lines["L position (feedback)"].split()[4] == "deg"
    assert "mm/s" in lines["TCP speed (feedback)"]
    assert "raw" in lines["TCP speed (feedback)"]
    assert "deg/s" in lines["S speed (feedback)"]
    for line in lines.values():  # every raw value with its unit, also where it is the same
        assert re.search(r"raw -?\d+ \S+$", line), line


def test_outputs_without_a_cell_file_says_what_it_needs() -> None:
    result = CliRunner().invoke(cli, ["mreg", "outputs", "--motion-port", "1"])
    assert result.exit_code == EXIT_USAGE
    assert "needs --config CELL.toml: its [groups.s1cxg] table" in result.output


def test_outputs_of_a_cell_without_a_table_says_so_before_connecting() -> None:
    fixture = CELL.parent / "hc10_table_fixture.toml"
    result = CliRunner().invoke(
        cli, ["mreg", "outputs", "--config", str(fixture), "--io-port", "1"]
    )  # port 1: nothing listens; the refusal comes first
    assert result.exit_code == EXIT_USAGE
    assert "hc10_table_fixture.toml has no [groups.s1cxg] table for group 0" in result.output
    assert "mreg read N" in result.output
