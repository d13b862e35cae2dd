"""Every pose the CLI prints names its frame (issue 29 item 5): ``base``, the S-axis
height above ``base_link`` taken from the robot model, in ``status`` (table, ``--watch``,
``--json``) and in ``move --pose``'s lines."""

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
from pymotoros.kinematics import chain_for
from pymotoros.models import robot_model

CELL = Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_register_outputs.toml"
HC10_BASE = "in base (0.275 m above base_link, the S-axis height)"


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


@pytest.fixture(scope="module")
def hc10() -> Iterator[Sim]:
    with running_sim("--config", str(CELL)) as s:
        yield s


def test_status_names_the_frame_of_the_tcp(hc10: Sim) -> None:
    table = invoke(hc10, "status", "--config", str(CELL), "--tool", "1").stdout
    tcp = next(line for line in table.splitlines() if line.strip().startswith("TCP"))
    where = table.splitlines()[table.splitlines().index(tcp) + 1]
    assert where.strip().startswith(HC10_BASE), table
    data = json.loads(invoke(hc10, "status", "--config", str(CELL), "--json").stdout)
    assert data["groups"][0]["tcp_frame"] == {"name": "base", "above_base_link_m": 0.275}
    watched = invoke(hc10, "status", "--watch", "--count", "1", "--config", str(CELL)).stdout
    assert HC10_BASE in watched  # tool unknown: tool0, in the same frame


def test_move_pose_lines_name_the_frame(hc10: Sim) -> None:
    assert invoke(hc10, "enable", "--config", str(CELL)).exit_code == 0
    moved = invoke(
        hc10, "move", "--pose", "0.6", "0.1", "0.3", "180", "0", "0", "--deg", "--tool", "1",
        "--config", str(CELL),
    )  # fmt: skip
    assert moved.exit_code == 0, moved.output
    lines = moved.stderr.splitlines()
    goal = next(line for line in lines if line.startswith("moving the TCP of tool 1"))
    pose = "x 600.0 y 100.0 z 300.0 mm  Rx 180.00 Ry 0.00 Rz 0.00 deg"
    assert goal.endswith(f"to {pose} {HC10_BASE}")
    reached = next(line for line in lines if line.startswith("the TCP stands at"))
    assert "x 600.0 y 100.0 z 300.0 mm" in reached
    assert reached.endswith(HC10_BASE)
    down = invoke(hc10, "move", "--relative", "dz=-0.05", "--tool", "1", "--config", str(CELL))
    assert down.exit_code == 0, down.output
    step = next(line for line in down.stderr.splitlines() if line.startswith("moving the TCP"))
    assert step.endswith(
        f"by dx 0.0 dy 0.0 dz -50.0 mm  drx 0.00 dry 0.00 drz 0.00 deg along {HC10_BASE}"
    )
    assert "z 250.0 mm" in next(ln for ln in down.stderr.splitlines() if ln.startswith("the TCP"))
    back = invoke(hc10, "move", "--relative", "dz=0.05", "--tool", "1", "--config", str(CELL))
    assert back.exit_code == 0, back.output
    # the same TCP 0.275 m lower in base_link: the numbers really are in base
    q = json.loads(invoke(hc10, "status", "--config", str(CELL), "--json").stdout)
    joints = q["groups"][0]["positions"]
    chain = chain_for("hc10")  # tool0: the gripper's TCP is 150 mm below it (pointing down)
    assert chain.pose(joints, "tool0", "base")[2] == pytest.approx(0.45, abs=1e-3)
    assert chain.pose(joints, "tool0", "base_link")[2] == pytest.approx(0.45 + 0.275, abs=1e-3)


def test_the_height_comes_from_the_model() -> None:
    """A GP7's base is 0.330 m above base_link: the CLI says so, nothing is hard-coded."""
    gp7 = robot_model("gp7").groups[0]
    assert gp7.base_height == pytest.approx(0.33)
    with running_sim("--robot", "gp7") as sim:
        table = invoke(sim, "status", "--robot", "gp7").stdout
    assert "in base (0.330 m above base_link, the S-axis height)" in table
