"""The robot models against the tables of shared/reference/robot-models.md."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pymotoros.errors import ConfigError
from pymotoros.models import (
    CONTROLLERS,
    ROBOTS,
    ControllerType,
    GroupKind,
    controller_model,
    robot_model,
)
from pymotoros.motion import GroupAxes

JOINT_TABLES = Path(__file__).with_name("joint_tables.txt")
"""(joint, lower °, upper °, speed °/s) per robot, transcribed from robot-models.md §1."""


def _joint_tables(text: str) -> dict[str, list[tuple[str, float, float, float]]]:
    """The ``[name]`` sections of a table such as JOINT_TABLES, a joint per row."""
    tables: dict[str, list[tuple[str, float, float, float]]] = {}
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line.startswith("["):
            rows = tables.setdefault(line.strip("[]"), [])
        elif line:
            joint, lower, upper, speed = line.split()
            rows.append((joint, float(lower), float(upper), float(speed)))
    return tables


TABLES = _joint_tables(JOINT_TABLES.read_text(encoding="utf-8"))
SDA_ARM = TABLES.pop("sda10f arm")
TABLES["hc10dt"] = TABLES["hc10"]


def test_every_robot_of_the_issue_is_there() -> None:
    assert set(ROBOTS) == {"hc10", "hc10dt", "gp7", "gp8", "gp12", "mh5", "sia20d", "sda10f"}
    assert robot_model("HC10") is ROBOTS["hc10"]
    with pytest.raises(ConfigError, match="known robots"):
        robot_model("hc20")


def test_hc10_summary_table_in_radians() -> None:
    # robot-models.md summary: lower, upper, max velocity (rad)
    expected = [
        (-3.141593, 3.141593, 2.268928),
        (-3.141593, 3.141593, 2.268928),
        (-0.087266, 6.195919, 3.141593),
        (-3.141593, 3.141593, 3.141593),
        (-3.141593, 3.141593, 4.363323),
        (-3.141593, 3.141593, 4.363323),
    ]
    axes = ROBOTS["hc10"].groups[0].axes
    for axis, (lo, hi, vel) in zip(axes, expected, strict=True):
        assert (axis.lower, axis.upper, axis.max_velocity) == pytest.approx((lo, hi, vel), abs=1e-6)


@pytest.mark.parametrize("name", sorted(TABLES))
def test_single_arm_limits_and_speeds(name: str) -> None:
    (group,) = ROBOTS[name].groups
    assert group.name == "R1"
    assert group.kind is GroupKind.ROBOT
    got = [
        (a.name, math.degrees(a.lower), math.degrees(a.upper), math.degrees(a.max_velocity))
        for a in group.axes
    ]
    assert [g[0] for g in got] == [t[0] for t in TABLES[name]]
    for g, t in zip(got, TABLES[name], strict=True):
        assert g[1:] == pytest.approx(t[1:], abs=1e-9)


def test_sda10f_groups() -> None:
    sda = ROBOTS["sda10f"]
    assert [g.name for g in sda.groups] == ["R1", "R2", "B1", "B2"]
    assert [g.kind for g in sda.groups] == [GroupKind.ROBOT] * 2 + [GroupKind.BASE] * 2
    for group, side in zip(sda.groups[:2], ("left", "right"), strict=True):
        assert group.moto_slots == (0, 1, 6, 2, 3, 4, 5)
        for axis, (joint, lo, hi, speed) in zip(group.axes, SDA_ARM, strict=True):
            assert axis.name == f"arm_{side}_{joint}"
            assert (math.degrees(axis.lower), math.degrees(axis.upper)) == pytest.approx((lo, hi))
            assert math.degrees(axis.max_velocity) == pytest.approx(speed)
    for group, joint in zip(sda.groups[2:], ("torso_joint_b1", "torso_joint_b2"), strict=True):
        (axis,) = group.axes
        assert axis.name == joint
        assert math.degrees(axis.upper) == pytest.approx(170)
        assert math.degrees(axis.max_velocity) == pytest.approx(130)
    assert len(sda.groups) <= CONTROLLERS[ControllerType.FS100].max_groups


def test_seven_axis_arms_use_the_controller_slot_order() -> None:
    assert ROBOTS["sia20d"].groups[0].moto_slots == (0, 1, 6, 2, 3, 4, 5)
    for name in ("hc10", "gp7", "mh5"):
        assert ROBOTS[name].groups[0].moto_slots == tuple(range(6))


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_model_sanity(name: str) -> None:
    robot = ROBOTS[name]
    known = {t.value for t in ControllerType}
    assert robot.controllers
    assert robot.controllers <= known
    names = [a.name for g in robot.groups for a in g.axes]
    assert len(names) == len(set(names))
    for group in robot.groups:
        assert len(group.dh) == group.num_axes
        assert len(group.home) == group.num_axes
        for axis in group.axes:
            assert axis.lower < 0 < axis.upper
            pulses_per_degree = axis.pulses_per_unit * math.pi / 180
            assert 450 <= pulses_per_degree <= 2000
            assert axis.max_acceleration > axis.max_velocity
            assert axis.max_jerk > axis.max_acceleration


@pytest.mark.parametrize("name", sorted(ROBOTS))
@pytest.mark.parametrize("controller", ["yrc1000", "fs100"])
def test_speed_limit_from_max_increment_is_the_datasheet_speed(name: str, controller: str) -> None:
    """MotoROS's limit (maxInc per 4 ms tick → pulses/s → rad/s) lands within a pulse/s
    of the datasheet speed, so the simulated robot refuses what the real one would."""
    ctrl = controller_model(controller)
    for group in ROBOTS[name].groups:
        axes = GroupAxes.from_model(group, ctrl)
        for i, axis in enumerate(group.axes):
            slot = group.moto_slots[i]
            datasheet_pps = axis.max_velocity * axis.pulses_per_unit
            assert abs(axes.max_speed_pulses[slot] - datasheet_pps) <= 1.0
            derived = axes.max_speed[i] * axes.pulses_per_unit[slot]
            assert abs(derived - datasheet_pps) <= 1.0
            assert axes.max_increment[slot] == axes.max_speed_pulses[slot] * 4 // 1000


def test_hc10_default_pairing() -> None:
    assert ROBOTS["hc10"].controllers == {"yrc1000", "yrc1000micro"}
    assert ROBOTS["sda10f"].controllers == {"fs100"}
