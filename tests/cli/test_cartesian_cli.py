"""``pymotoros move --pose`` / ``--relative`` and the TCP in ``status``, against the sim."""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_USAGE
from pymotoros.kinematics import chain_for

START = ("0", "0.5", "1.9", "0", "0.9", "0")
MM = 1e-3


sim = sim_fixture()


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


def _tcp(sim: Sim) -> list[float]:
    data = json.loads(invoke(sim, "status", "--json").stdout)
    tcp = data["groups"][0]["tcp"]
    assert tcp is not None
    return [float(v) for v in tcp]


def test_relative_and_pose_moves(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    assert invoke(sim, "move", *START).exit_code == 0
    before = _tcp(sim)
    expected = chain_for("hc10").pose([float(v) for v in START])
    assert before == pytest.approx(expected, abs=1e-4)
    table = invoke(sim, "status")
    assert "in base (0.275 m above base_link, the S-axis height)" in table.output

    result = invoke(sim, "move", "--relative", "dz=-0.05", "--json")
    assert result.exit_code == 0, result.output
    after = _tcp(sim)
    assert after[2] == pytest.approx(before[2] - 0.05, abs=0.1 * MM)
    assert after[:2] == pytest.approx(before[:2], abs=0.1 * MM)

    x, y, z = after[0] + 0.02, after[1], after[2]
    rx, ry, rz = (math.degrees(a) for a in after[3:])
    args = [f"{v:.6f}" for v in (x, y, z, rx, ry, rz)]
    result = invoke(sim, "move", "--pose", *args, "--deg", "--linear", "--tcp-speed", "100")
    assert result.exit_code == 0, result.output
    assert _tcp(sim)[:3] == pytest.approx([x, y, z], abs=0.1 * MM)

    result = invoke(sim, "move", "--relative", "dz=0.03", "--frame", "tool")
    assert result.exit_code == 0, result.output


def test_cartesian_usage_errors(sim: Sim) -> None:
    result = invoke(sim, "move", "--pose", "1", "2", "3")
    assert result.exit_code == EXIT_USAGE
    assert "6 values" in result.stderr
    result = invoke(sim, "move", "--relative", "dq=1")
    assert result.exit_code == EXIT_USAGE
    assert "dx, dy, dz" in result.stderr
    result = invoke(sim, "move", "--linear", "0", "0", "0", "0", "0", "0")
    assert result.exit_code == EXIT_USAGE
    assert "--linear goes with --pose" in result.stderr


# --------------------------------------------------------------------------- the tool is the TCP

CELL = Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_register_outputs.toml"
"""Tool 1 of this cell is a 150 mm gripper (issue 20)."""
REQUEST = ("0.6", "0.1", "0.3", "180", "0", "0")


@pytest.fixture(scope="module")
def gripper_sim() -> Iterator[Sim]:
    with running_sim("--config", str(CELL)) as s:
        yield s


def in_cell(sim: Sim, *args: str, env: dict[str, str] | None = None) -> Result:
    return CliRunner(env=env).invoke(
        cli, [*args, *sim.cli_args(), "--config", str(CELL)], catch_exceptions=False
    )


def _twin_tcp(sim: Sim) -> list[float]:
    """The TCP as the sim computes it with the tool its controller has selected."""
    return [float(v) for v in sim.api("/api/state")["groups"][0]["tcp"]["feedback"]]


def test_a_pose_move_places_the_selected_tools_tcp(gripper_sim: Sim) -> None:
    request = [0.6, 0.1, 0.3, math.pi, 0.0, 0.0]
    assert in_cell(gripper_sim, "enable").exit_code == 0
    assert in_cell(gripper_sim, "tool", "1").exit_code == 0
    before = _twin_tcp(gripper_sim)

    # Another process selected tool 1: this one cannot know it, and refuses to guess.
    refused = in_cell(gripper_sim, "move", "--pose", *REQUEST, "--deg")
    assert refused.exit_code == EXIT_USAGE, refused.output
    assert "--tool N" in refused.stderr
    assert "tool 1 (gripper, TCP x 0.0 y 0.0 z 150.0 mm on tool0)" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
    assert _twin_tcp(gripper_sim) == pytest.approx(before, abs=1e-6)

    done = in_cell(gripper_sim, "move", "--pose", *REQUEST, "--deg", "--tool", "1")
    assert done.exit_code == 0, done.output
    assert "moving the TCP of tool 1 (gripper" in done.stderr
    assert _twin_tcp(gripper_sim) == pytest.approx(request, abs=MM)  # within 1 mm

    data = json.loads(in_cell(gripper_sim, "status", "--json", "--tool", "1").stdout)
    group = data["groups"][0]
    assert group["tcp"] == pytest.approx(request, abs=MM)
    assert group["tool"]["number"] == 1
    assert group["tool"]["tcp_m"] == [0.0, 0.0, 0.15]
    table = in_cell(gripper_sim, "status", env={"PYMOTOROS_TOOL": "1"}).output
    assert "tool 1 (gripper, TCP x 0.0 y 0.0 z 150.0 mm on tool0)" in table
    assert "z 300.0 mm" in table

    unknown = in_cell(gripper_sim, "status").output
    assert "    tool0  " in unknown
    assert "z 450.0 mm" in unknown  # tool0, 150 mm above the gripper's TCP
    assert "TCP unknown: name the tool in force with --tool N" in unknown


def test_a_linear_move_with_the_gripper(gripper_sim: Sim) -> None:
    assert in_cell(gripper_sim, "enable").exit_code == 0
    start = ("0.55", "0.1", "0.35", "180", "0", "0")
    assert in_cell(gripper_sim, "move", "--pose", *start, "--deg", "--tool", "1").exit_code == 0
    result = in_cell(gripper_sim, "move", "--pose", *REQUEST, "--deg", "--linear", "--tool", "1")
    assert result.exit_code == 0, result.output
    assert _twin_tcp(gripper_sim) == pytest.approx([0.6, 0.1, 0.3, math.pi, 0, 0], abs=MM)
    result = in_cell(gripper_sim, "move", "--relative", "dz=0.05", "--tool", "1")
    assert result.exit_code == 0, result.output
    assert _twin_tcp(gripper_sim)[2] == pytest.approx(0.35, abs=MM)


def test_the_settings_file_names_the_tool(gripper_sim: Sim, tmp_path: Path) -> None:
    settings = tmp_path / "pymotoros.toml"
    settings.write_text("[status]\ntool = 1\n", encoding="utf-8")
    table = in_cell(gripper_sim, "status", env={"PYMOTOROS_SETTINGS": str(settings)}).output
    assert "tool 1 (gripper, TCP x 0.0 y 0.0 z 150.0 mm on tool0)" in table
