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
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.robot import EXIT_USAGE
from pymotoros.kinematics import chain_for

START = ("0", "0.5", "1.9", "0", "0.9", "0")
MM = 1e-3


@pytest.fixture(scope="module")
def sim() -> Iterator[Sim]:
    with running_sim() as s:
        yield s


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
    assert "TCP (base)" in table.output

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
