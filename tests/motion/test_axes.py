"""Joint order, conversions and the per-group constants (§5.5, §5.7)."""

from __future__ import annotations

import pytest

from pymotoros.errors import ConfigError
from pymotoros.models import controller_model, robot_model
from pymotoros.motion import GroupAxes, TrajPoint, from_pulses, interpolate, to_pulses

from .helpers import axes_for


def test_seven_axis_order() -> None:
    sia = axes_for("sia20d", "dx100")
    assert sia.ros_to_slot[:7] == (0, 1, 6, 2, 3, 4, 5)
    assert sia.axis_slots == (0, 1, 2, 3, 4, 5, 6)
    assert sia.slot_to_ros[:7] == (0, 1, 3, 4, 5, 6, 2)
    assert sia.joint_at_slot(6) == "joint_e"
    # ROS positions S,L,E,U,R,B,T = 1..7 pulses each end up as S,L,U,R,B,T,E
    pos = tuple((k + 1.5) / sia.pulses_per_unit[sia.ros_to_slot[k]] for k in range(7))
    assert to_pulses(pos, sia) == (1, 2, 4, 5, 6, 7, 3, 0)
    back = from_pulses((1, 2, 4, 5, 6, 7, 3, 0), sia)
    assert [round(b * sia.pulses_per_unit[sia.ros_to_slot[k]]) for k, b in enumerate(back[:7])] == [
        1,
        2,
        3,
        4,
        5,
        6,
        7,
    ]


def test_moving_only_the_elbow_moves_the_last_controller_column() -> None:
    sia = axes_for("sia20d", "dx100")
    start = TrajPoint(0.0, (0.0,) * 7, (0.0,) * 7)
    end = TrajPoint(0.1005, (0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0), (0.0,) * 7)
    _, incs = interpolate([start, end], sia)
    assert (incs[:, :6] == 0).all()
    assert int(incs[:, 6].sum()) == to_pulses(end.pos, sia)[6]


def test_invalid_slots_convert_with_factor_one(hc10: GroupAxes) -> None:
    assert to_pulses((0.0,) * 6 + (12.7, -3.9), hc10)[6:] == (12, -3)
    assert from_pulses((0,) * 6 + (5, 0), hc10)[6] == 5.0


def test_pulses_per_unit_are_float32_in_controller_order(hc10: GroupAxes) -> None:
    import numpy as np

    for value in hc10.pulses_per_unit:
        assert float(np.float32(value)) == value
    assert hc10.valid == (True,) * 6 + (False, False)


def test_bad_overrides_are_config_errors() -> None:
    group = robot_model("hc10").groups[0]
    ctrl = controller_model("yrc1000")
    with pytest.raises(ConfigError, match="6 axes"):
        GroupAxes.from_model(group, ctrl, [1.0] * 5)
    with pytest.raises(ConfigError, match="joint_3_u"):
        GroupAxes.from_model(group, ctrl, [1.0, 1.0, -2.0, 1.0, 1.0, 1.0])


def test_multi_group_robot_gives_one_axes_per_group() -> None:
    sda = robot_model("sda10f")
    fs100 = controller_model("fs100")
    groups = [GroupAxes.from_model(g, fs100) for g in sda.groups]
    assert [g.num_axes for g in groups] == [7, 7, 1, 1]
    assert groups[2].joint_names == ("torso_joint_b1",)
    assert groups[0].ros_to_slot[:7] == (0, 1, 6, 2, 3, 4, 5)
