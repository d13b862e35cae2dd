"""The robot models against the tables of shared/reference/robot-models.md."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from pymotoros.errors import ConfigError
from pymotoros.models import (
    CONTROLLERS,
    ROBOTS,
    ControllerType,
    GroupKind,
    GroupModel,
    RobotModel,
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


def _gp7_arm(**changes: object) -> GroupModel:
    """The GP7's R1 declared again field by field (no ``link_radii`` unless given), as a
    new model's author writes it."""
    gp7 = ROBOTS["gp7"].groups[0]
    group = GroupModel(
        gp7.name, gp7.kind, gp7.axes, gp7.moto_slots, gp7.home, gp7.dh, tool0=gp7.tool0
    )
    return dataclasses.replace(group, **changes)


def test_a_robot_group_declared_without_shapes_is_refused() -> None:
    """Without capsule radii the arm would have no collision body and pass through every
    obstacle: the declaration itself fails, naming the model, the group and the fix."""
    with pytest.raises(ConfigError) as err:
        RobotModel("toy", "a toy arm", (_gp7_arm(),), frozenset({"yrc1000"}))
    assert str(err.value) == (
        "robot model 'toy' group R1 has no collision shapes, so obstacles would never stop "
        "it: declare link_radii on the group, 7 capsule radii in m (the base link's, then "
        "one per joint's link in ROS order)"
    )


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        (
            {"link_radii": (0.1,) * 6},
            "robot model 'toy' group R1: 6 link_radii for 6 axes; give 7 (the base link's, "
            "then one per joint's link in ROS order)",
        ),
        (
            {"link_radii": (0.1, 0.1, 0.0, 0.1, 0.1, 0.1, 0.1)},
            "robot model 'toy' group R1: link_radii[2] is 0.0, a capsule radius is > 0 m",
        ),
        (
            {"link_radii": (0.1,) * 7, "kind": GroupKind.STATION, "name": "S1"},
            "robot model 'toy' group S1 is a station axis group: it takes no link_radii "
            "(only robot groups R1, R2 … have collision shapes)",
        ),
    ],
)
def test_wrong_shapes_are_refused(changes: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError) as err:
        RobotModel("toy", "a toy arm", (_gp7_arm(**changes),), frozenset({"yrc1000"}))
    assert str(err.value) == message


def test_a_robot_group_without_joint_geometry_has_no_shapes_and_is_refused() -> None:
    axes = tuple(dataclasses.replace(a, geometry=None) for a in ROBOTS["gp7"].groups[0].axes)
    group = _gp7_arm(axes=axes, link_radii=(0.1,) * 7)
    with pytest.raises(ConfigError, match=r"'toy' group R1 has no collision shapes: joint_1_s"):
        RobotModel("toy", "a toy arm", (group,), frozenset({"yrc1000"}))


def test_the_same_arm_with_shapes_is_a_robot() -> None:
    radii = (0.12, 0.1, 0.07, 0.07, 0.05, 0.045, 0.035)
    toy = RobotModel("toy", "a toy arm", (_gp7_arm(link_radii=radii),), frozenset({"yrc1000"}))
    assert toy.groups[0].link_radii == radii


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_every_shipped_robot_group_has_shapes(name: str) -> None:
    """Each robot group a capsule radius per link (base link first), each base or station
    axis none (the SDA10F torso: the arms' base links cover it)."""
    for group in ROBOTS[name].groups:
        if group.kind is GroupKind.ROBOT:
            assert len(group.link_radii) == group.num_axes + 1
            assert all(0.02 <= r <= 0.2 for r in group.link_radii)
            assert all(a.geometry is not None for a in group.axes)
        else:
            assert group.link_radii == ()
