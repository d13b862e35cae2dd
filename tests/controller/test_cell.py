"""Cell configuration: TOML files, defaults, and errors that name the key."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from pymotoros.controller import VirtualController, cell_from_dict, default_cell, load_cell
from pymotoros.errors import ConfigError
from pymotoros.models.robots import ROBOTS
from pymotoros.protocol.constants import NotReadySubcode as Nr
from pymotoros.protocol.constants import PendantMode

from .helpers import CMD, command

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "cells"


def test_default_cell_is_an_hc10_on_a_yrc1000() -> None:
    cell = default_cell()
    assert cell.controller.type.value == "yrc1000"
    assert cell.robots == ("hc10",)
    assert cell.pfl
    assert cell.job_variant == "single_arm"
    assert cell.initial.mode is PendantMode.PLAY
    assert cell.initial.remote
    assert not cell.initial.servo
    assert cell.warnings == ()


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_the_pfl_option_comes_from_the_robot_model(robot: str) -> None:
    """PFL is a property of the (collaborative) arm, not of its name; only on YRC1000 builds."""
    model = ROBOTS[robot]
    assert model.pfl == (robot in {"hc10", "hc10dt"})
    assert default_cell("yrc1000", robot).pfl == model.pfl
    assert cell_from_dict({"robot": {"model": robot}}).pfl == model.pfl
    assert not default_cell("dx200", robot).pfl  # the DX200 build has no PFL support


def test_example_files_load() -> None:
    files = sorted(EXAMPLES.glob("*.toml"))
    assert files
    for f in files:
        vc = VirtualController(load_cell(f))
        assert command(vc, CMD.START_TRAJ_MODE).ok, f.name


def test_full_file(tmp_path: Path) -> None:
    f = tmp_path / "cell.toml"
    f.write_text(
        """
name = "test cell"
[controller]
model = "YRC1000micro"
servo_on_delay_ms = 200
feedback_lag_ticks = 1
feedback_noise_pulses = 2
[robot]
model = "hc10"
[[tools]]
number = 3
name = "gripper"
mass_kg = 1.5
tcp_m = [0, 0, 0.12]
[initial]
servo = true
joints.R1 = [0.1, 0.2, 0.3, 0.0, 0.0, 0.0]
tool.R1 = 3
""",
        encoding="utf-8",
    )
    cell = load_cell(f)
    assert cell.name == "test cell"
    assert cell.controller.type.value == "yrc1000micro"
    assert cell.servo.servo_on_delay_ms == 200
    assert cell.tools[0].tcp_m == (0.0, 0.0, 0.12)
    vc = VirtualController(cell)
    snap = vc.snapshot()
    assert snap.servo
    assert snap.groups[0].tool == 3
    assert snap.groups[0].command_rad[:3] == pytest.approx((0.1, 0.2, 0.3), abs=1e-4)
    vc.run_ticks(3)
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.NOT_STARTED


@pytest.mark.parametrize(
    ("data", "key", "problem"),
    [
        ({"controller": {"model": "r30ib"}}, "controller.model", "unknown controller"),
        ({"robot": {"model": "ur5"}}, "robot.model", "unknown robot"),
        ({"robot": {"modle": "hc10"}}, "robot.modle", "unknown key"),
        ({"controler": {}}, "controler", "unknown key"),
        ({"controller": {"servo_on_delay_ms": -1}}, "controller.servo_on_delay_ms", "0..4900"),
        ({"controller": {"feedback_noise_pulses": 50}}, "feedback_noise_pulses", "0..10"),
        ({"controller": {"jobs": 3}}, "controller.jobs", "must be"),
        ({"controller": {"model": "dx200", "pfl": True}}, "controller.pfl", "no PFL"),
        ({"groups": []}, "groups", "at least one"),
        ({"groups": [{"robot": "hc10", "group": "R7"}]}, "groups[0].group", "no group"),
        ({"groups": [{"robot": 5}]}, "groups[0].robot", "must be a string"),
        ({"initial": {"mode": "auto"}}, "initial.mode", "'play' or 'teach'"),
        ({"initial": {"servo": "yes"}}, "initial.servo", "true or false"),
        ({"initial": {"joints": {"R1": [0, 0]}}}, "initial.joints.R1", "needs 6 values"),
        ({"initial": {"joints": {"R1": [9, 0, 0, 0, 0, 0]}}}, "initial.joints.R1", "limits"),
        ({"initial": {"joints": {"R2": [0] * 6}}}, "initial.joints.R2", "no such group"),
        ({"initial": {"tool": {"R1": 64}}}, "initial.tool.R1", "0..63"),
        ({"initial": {"alarms": [{"subcode": 1}]}}, "initial.alarms[0].code", "required"),
        ({"initial": {"servo": True, "estop": True}}, "initial.servo", "E-stop"),
        ({"tools": [{"number": 1}, {"number": 1}]}, "tools", "twice"),
        ({"tools": [{"number": 1, "tcp_m": [0, 0]}]}, "tools[0].tcp_m", "three numbers"),
    ],
)
def test_errors_name_the_key(data: dict[str, object], key: str, problem: str) -> None:
    with pytest.raises(ConfigError) as info:
        cell_from_dict(data, source="cell.toml")
    message = str(info.value)
    assert message.startswith("cell.toml: "), message
    assert key in message, message
    assert problem in message, message


def test_bad_toml(tmp_path: Path) -> None:
    f = tmp_path / "bad.toml"
    f.write_text("[controller\nmodel=", encoding="utf-8")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_cell(f)
    with pytest.raises(ConfigError, match="cannot read"):
        load_cell(tmp_path / "missing.toml")


def test_unreal_combination_is_allowed_with_a_warning(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING):
        cell = default_cell("fs100", "hc10")
    assert cell.warnings
    assert "fs100" in cell.warnings[0]
    assert "not sold" in caplog.text
    assert not cell.pfl  # FS100 builds have no PFL support
    VirtualController(cell)


def test_groups_beyond_the_controller_are_ignored() -> None:
    cell = cell_from_dict(
        {"controller": {"model": "dx100"}, "groups": [{"robot": "hc10"}] * 4}, source="x"
    )
    assert [g.name for g in cell.groups] == ["R1", "R2", "R3"]
    assert any("at most 3" in w for w in cell.warnings)


def test_initial_state_from_the_file() -> None:
    cell = cell_from_dict(
        {
            "initial": {
                "mode": "teach",
                "remote": False,
                "alarms": [{"code": 4100, "subcode": 2, "text": "OVERRUN"}],
            }
        }
    )
    vc = VirtualController(cell)
    snap = vc.snapshot()
    assert snap.mode is PendantMode.TEACH
    assert not snap.remote
    assert [a.code for a in snap.alarms] == [4100]
    assert vc.robot_status().error_code == 4100
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.ALARM


def test_bad_job_file_is_a_config_error(tmp_path: Path) -> None:
    (tmp_path / "INIT_ROS.JBI").write_text(
        "/JOB\r\n//NAME INIT_ROS\r\n//INST\r\nNOP\r\nMOVL V=100\r\nEND\r\n", newline=""
    )
    (tmp_path / "cell.toml").write_text('[controller]\njobs = "."\n', encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        load_cell(tmp_path / "cell.toml")
    message = str(info.value)
    assert "controller.jobs" in message
    assert "INIT_ROS.JBI, line 5: unsupported instruction 'MOVL'" in message
