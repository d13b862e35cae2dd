"""``pymotoros urdf``: stdout by default, a file with -o, a clear error for a bad model."""

from __future__ import annotations

from pathlib import Path

import pinocchio as pin
from click.testing import CliRunner

from pymotoros.cli.main import cli


def test_urdf_to_stdout_parses_with_every_joint() -> None:
    result = CliRunner().invoke(cli, ["urdf", "--robot", "gp7"])
    assert result.exit_code == 0, result.output
    model = pin.buildModelFromXML(result.output)
    assert [model.names[i] for i in range(1, model.njoints)] == [
        "joint_1_s",
        "joint_2_l",
        "joint_3_u",
        "joint_4_r",
        "joint_5_b",
        "joint_6_t",
    ]
    assert model.existFrame("tool0")
    assert model.existFrame("base")


def test_urdf_to_a_file(tmp_path: Path) -> None:
    out = tmp_path / "hc10.urdf"
    result = CliRunner().invoke(cli, ["urdf", "--robot", "HC10", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert result.output == ""
    assert pin.buildModelFromXML(out.read_text(encoding="utf-8")).nq == 6


def test_urdf_of_an_unknown_robot_lists_the_known_ones() -> None:
    result = CliRunner().invoke(cli, ["urdf", "--robot", "nope"])
    assert result.exit_code == 2
    assert "known robots" in result.output
    assert "hc10" in result.output
