"""The trajectory file model: three formats, round trips, ROS 1 and ROS 2 YAML, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pymotoros.models import robot_model
from pymotoros.trajectory.files import (
    Trajectory,
    TrajectoryFileError,
    parse_csv,
    parse_json,
    parse_yaml,
    read_trajectory_file,
    to_json,
    to_yaml,
    write_trajectory_file,
)

HC10 = robot_model("hc10")
SDA10F = robot_model("sda10f")

ROS1_ECHO = """\
header:
  seq: 3
  stamp:
    secs: 1700000000
    nsecs: 120000000
  frame_id: "base_link"
joint_names: [joint_1_s, joint_2_l, joint_3_u, joint_4_r, joint_5_b, joint_6_t]
points:
  -
    positions: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    velocities: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    accelerations: []
    effort: []
    time_from_start:
      secs: 0
      nsecs:         0
  -
    positions: [0.1, 0.0, 0.05, 0.0, -0.1, 0.0]
    velocities: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    accelerations: []
    effort: []
    time_from_start:
      secs: 1
      nsecs: 500000000
---
"""

ROS2_ECHO = """\
header:
  stamp:
    sec: 0
    nanosec: 0
  frame_id: ''
joint_names:
- joint_1_s
- joint_2_l
- joint_3_u
- joint_4_r
- joint_5_b
- joint_6_t
points:
- positions:
  - 0.0
  - 0.0
  - 0.0
  - 0.0
  - 0.0
  - 0.0
  velocities: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
  accelerations: []
  effort: []
  time_from_start:
    sec: 0
    nanosec: 0
- positions: [0.1, 0.0, 0.05, 0.0, -0.1, 0.0]
  velocities: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
  accelerations: []
  effort: []
  time_from_start:
    sec: 2
    nanosec: 250000000
---
"""


def _sample(names: tuple[str, ...], points: int = 4) -> Trajectory:
    rng = np.random.default_rng(7)
    n = len(names)
    return Trajectory(
        names,
        np.arange(points) * 0.1 + np.array([0.0] + [0.0005] * (points - 1)),
        rng.uniform(-0.05, 0.05, (points, n)),
        rng.uniform(-0.2, 0.2, (points, n)),
        robot="hc10" if n == 6 else "sda10f",
        controller="yrc1000" if n == 6 else "dx200",
    )


def test_ros1_echo_yaml_is_read() -> None:
    traj = parse_yaml(ROS1_ECHO)
    assert traj.joint_names == HC10.groups[0].joint_names
    assert traj.times.tolist() == [0.0, 1.5]
    assert traj.positions[1].tolist() == [0.1, 0.0, 0.05, 0.0, -0.1, 0.0]


def test_ros2_echo_yaml_is_read() -> None:
    traj = parse_yaml(ROS2_ECHO)
    assert traj.times.tolist() == [0.0, 2.25]
    assert traj.positions[1, 4] == -0.1


@pytest.mark.parametrize("suffix", ["csv", "json", "yaml"])
def test_round_trip_single_group(tmp_path: Path, suffix: str) -> None:
    traj = _sample(HC10.groups[0].joint_names)
    path = tmp_path / f"t.{suffix}"
    write_trajectory_file(traj, path)
    back = read_trajectory_file(path, HC10)
    assert back.joint_names == traj.joint_names
    np.testing.assert_allclose(back.times, traj.times, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(back.positions, traj.positions)
    np.testing.assert_array_equal(back.velocities, traj.velocities)


@pytest.mark.parametrize("suffix", ["json", "yaml"])
def test_multi_group_round_trip_and_split(tmp_path: Path, suffix: str) -> None:
    names = tuple(n for g in SDA10F.groups for n in g.joint_names)
    traj = _sample(names)
    path = tmp_path / f"t.{suffix}"
    write_trajectory_file(traj, path)
    back = read_trajectory_file(path)
    np.testing.assert_array_equal(back.positions, traj.positions)
    columns = back.group_columns(SDA10F)
    assert [g for g, _ in columns] == [0, 1, 2, 3]
    assert [len(c) for _, c in columns] == [7, 7, 1, 1]


def test_groups_may_be_given_in_any_joint_order() -> None:
    left, right = SDA10F.groups[0].joint_names, SDA10F.groups[1].joint_names
    names = tuple(reversed(right)) + left
    traj = _sample(names, 2)
    columns = traj.group_columns(SDA10F)
    assert columns[0] == (0, list(range(7, 14)))
    assert columns[1] == (1, list(range(6, -1, -1)))


def test_csv_refuses_multi_group_robots() -> None:
    with pytest.raises(TrajectoryFileError, match="one control group"):
        parse_csv("time\n0\n", SDA10F)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (ROS1_ECHO + ROS1_ECHO, "holds 2 messages"),
        ("joint_names: [a]\n", "not a trajectory_msgs/JointTrajectory"),
        (ROS1_ECHO.replace("secs: 1\n", "secs: x\n"), "integer secs"),
        (ROS1_ECHO.replace("[0.1, 0.0, 0.05, 0.0, -0.1, 0.0]", "[0.1]"), "point 1 positions"),
    ],
)
def test_bad_yaml_says_what_is_wrong(text: str, message: str) -> None:
    with pytest.raises(TrajectoryFileError, match=message):
        parse_yaml(text)


def test_bad_json_and_partial_groups() -> None:
    good = to_json(_sample(HC10.groups[0].joint_names))
    with pytest.raises(TrajectoryFileError, match="version"):
        parse_json(good.replace('"version": 1', '"version": 9'))
    with pytest.raises(TrajectoryFileError, match="unknown key"):
        parse_json(good.replace('"time":', '"acc": 1, "time":', 1))
    partial = Trajectory(
        SDA10F.groups[0].joint_names[:3], np.zeros(1), np.zeros((1, 3)), np.zeros((1, 3))
    )
    with pytest.raises(TrajectoryFileError, match="named only partly"):
        partial.group_columns(SDA10F)
    with pytest.raises(TrajectoryFileError, match="has no joint"):
        parse_yaml(to_yaml(_sample(("nope",) * 1, 2))).group_columns(HC10)


def test_non_finite_values_are_refused() -> None:
    with pytest.raises(TrajectoryFileError, match="point 1: a position"):
        Trajectory(("a",), np.array([0.0, 1.0]), np.array([[0.0], [np.nan]]), np.zeros((2, 1)))


@pytest.mark.parametrize("value", ["true", '"0.5"', "null"])
def test_a_position_that_is_not_a_json_number_is_refused(value: str) -> None:
    """``true`` and ``"0.5"`` pass ``float()``; a trajectory file's values are numbers only
    (found by the bad-file Hypothesis test: ``true`` was read as 1.0 rad)."""
    good = to_json(_sample(HC10.groups[0].joint_names))
    head, sep, tail = good.partition('"positions": [')
    bad = head + sep + value + tail[tail.index(","):]
    with pytest.raises(TrajectoryFileError, match="not all numbers"):
        parse_json(bad)
