"""ROS ↔ controller joint order (reference §5.7), checked against hand-written tables."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol.joint_order import (
    IDENTITY,
    SEVEN_AXIS,
    check_map,
    packed_map,
    ros_to_slot_map,
    to_controller_order,
    to_ros_order,
)

CONTROLLER_7 = ("S", "L", "U", "R", "B", "T", "E", "-")
ROS_7 = ("S", "L", "E", "U", "R", "B", "T", "-")


def test_seven_axis_arm() -> None:
    assert to_ros_order(CONTROLLER_7, SEVEN_AXIS) == ROS_7
    assert to_controller_order(ROS_7, SEVEN_AXIS) == CONTROLLER_7


def test_seven_axis_rule_from_the_reference() -> None:
    """ROS[0] = Moto[0], ROS[1] = Moto[1], ROS[2] = Moto[6], ROS[k] = Moto[k−1] for k = 3..6."""
    moto = tuple(range(10, 18))
    ros = to_ros_order(moto, SEVEN_AXIS)
    assert ros[0] == moto[0]
    assert ros[1] == moto[1]
    assert ros[2] == moto[6]
    for k in range(3, 7):
        assert ros[k] == moto[k - 1]


@pytest.mark.parametrize(
    ("controller", "ros"),
    [
        ("SLU--T--", "SLUT----"),  # delta, large palletiser
        ("SLU-BT--", "SLUBT---"),  # high-speed picker
        ("SLUR----", "SLUR----"),  # SCARA: already packed
    ],
)
def test_fewer_than_six_axes_are_packed(controller: str, ros: str) -> None:
    valid = [c != "-" for c in controller]
    mapping = ros_to_slot_map(valid, robot=True)
    assert "".join(to_ros_order(tuple(controller), mapping)) == ros
    assert "".join(to_controller_order(tuple(ros), mapping)) == controller


@pytest.mark.parametrize(
    ("valid", "robot", "expected"),
    [
        ([1, 1, 1, 1, 1, 1, 0, 0], True, IDENTITY),
        ([1, 1, 1, 1, 1, 1, 1, 0], True, SEVEN_AXIS),
        ([1, 1, 1, 1, 1, 1, 1, 0], False, IDENTITY),  # a 7-axis station is not reordered
        ([1, 0, 0, 0, 0, 0, 0, 0], False, IDENTITY),  # a 1-axis base is not packed
        ([1, 1, 1, 0, 0, 1, 0, 0], True, (0, 1, 2, 5, 3, 4, 6, 7)),
    ],
)
def test_map_choice(valid: list[int], robot: bool, expected: tuple[int, ...]) -> None:
    assert ros_to_slot_map([bool(v) for v in valid], robot=robot) == expected


def test_packed_map_puts_unused_slots_last() -> None:
    assert packed_map([False, True, False, True, False, False, False, True]) == (
        1,
        3,
        7,
        0,
        2,
        4,
        5,
        6,
    )


@given(st.permutations(list(range(8))), st.lists(st.integers(), min_size=8, max_size=8))
def test_conversions_are_inverse(mapping: list[int], values: list[int]) -> None:
    assert to_ros_order(to_controller_order(values, mapping), mapping) == tuple(values)
    assert to_controller_order(to_ros_order(values, mapping), mapping) == tuple(values)


def test_ten_slot_arrays_use_the_first_eight() -> None:
    assert to_ros_order(tuple(range(10)), SEVEN_AXIS) == (0, 1, 6, 2, 3, 4, 5, 7)


def test_short_input_and_bad_map() -> None:
    with pytest.raises(LocalProtocolError):
        to_ros_order((1, 2, 3), IDENTITY)
    with pytest.raises(LocalProtocolError):
        check_map((0, 0, 1, 2, 3, 4, 5, 6))
    assert check_map(SEVEN_AXIS) == SEVEN_AXIS
