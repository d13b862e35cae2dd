"""The point checks: 3011, 3013 (with the truncation quirk), 3016, and their order."""

from __future__ import annotations

import logging

import pytest

from pymotoros.errors import TrajectoryRejectedError
from pymotoros.motion import (
    GroupAxes,
    TrajPoint,
    check_speed,
    check_start,
    check_time,
    interpolate,
    to_pulses,
)
from pymotoros.protocol.constants import InvalidSubcode

from .helpers import axes_for

ZERO6 = (0.0,) * 6


def test_hc10_limits_in_rad_per_s(hc10: GroupAxes) -> None:
    # 741 pulses per 4 ms at 1425 pulses/° → 185250 pulses/s → exactly 130°/s
    assert hc10.max_increment[:6] == (741, 741, 900, 666, 910, 650)
    assert hc10.max_speed_pulses[0] == 185250
    assert hc10.max_speed[0] == pytest.approx(2.268928, abs=1e-6)
    assert hc10.max_speed[6:] == (0.0, 0.0)


@pytest.mark.parametrize(
    ("speed", "refused"),
    [(2.2, False), (2.9, False), (2.999, False), (3.0, True), (-2.9, False), (-3.0, True)],
)
def test_speed_check_truncates_the_velocity_first(
    hc10: GroupAxes, speed: float, refused: bool
) -> None:
    # S axis limit 2.2689 rad/s: trunc(|v|) > 2.2689 only from 3 rad/s on
    point = TrajPoint(0.1, ZERO6, (speed,) + (0.0,) * 5)
    refusal = check_speed(point, hc10)
    assert (refusal is not None) == refused
    if refusal is not None:
        assert refusal.subcode is InvalidSubcode.DATA_SPEED
        assert refusal.axis == 0
        assert refusal.joint == "joint_1_s"
        assert refusal.value == pytest.approx(abs(speed))
        assert refusal.limit == pytest.approx(2.268928, abs=1e-6)
        assert "truncates |v| to 3" in refusal.message
        assert "3013" in refusal.message
        assert "pulses/s" in refusal.message


def test_the_quirk_is_logged_when_it_lets_a_speed_through(
    hc10: GroupAxes, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.WARNING, logger="pymotoros.motion"):
        assert check_speed(TrajPoint(0.1, ZERO6, (2.9,) + (0.0,) * 5), hc10) is None
    assert "joint_1_s" in caplog.text
    assert "truncates" in caplog.text


def test_sequence_gt_0_ignores_slots_past_the_last_axis(hc10: GroupAxes) -> None:
    point = TrajPoint(0.1, ZERO6, (0.0,) * 6 + (5.0,))
    assert check_speed(point, hc10) is None
    start = TrajPoint(0.0, ZERO6, (0.0,) * 6 + (0.99,))
    assert check_start(start, to_pulses(ZERO6, hc10), hc10) is None
    start = TrajPoint(0.0, ZERO6, (0.0,) * 6 + (1.0,))
    refusal = check_start(start, to_pulses(ZERO6, hc10), hc10)
    assert refusal is not None
    assert refusal.subcode is InvalidSubcode.DATA_SPEED
    assert refusal.axis == 6


def test_start_position_tolerance_is_30_pulses_against_the_commanded_position(
    hc10: GroupAxes,
) -> None:
    commanded = (100, 200, 300, 400, 500, 600, 0, 0)
    pos = tuple((c + 30.5) / hc10.pulses_per_unit[i] for i, c in enumerate(commanded[:6]))
    assert check_start(TrajPoint(0.0, pos, ZERO6), commanded, hc10) is None
    far = (pos[0], (commanded[1] + 31.5) / hc10.pulses_per_unit[1], *pos[2:])
    refusal = check_start(TrajPoint(0.0, far, ZERO6), commanded, hc10)
    assert refusal is not None
    assert refusal.subcode is InvalidSubcode.DATA_START_POS
    assert (refusal.axis, refusal.joint, refusal.value, refusal.limit) == (
        1,
        "joint_2_l",
        31.0,
        30.0,
    )
    assert "231 pulses" in refusal.message
    assert "200 pulses" in refusal.message
    assert "rad" in refusal.message
    assert "3011" in refusal.message


def test_position_and_speed_are_interleaved_per_index(hc10: GroupAxes) -> None:
    commanded = to_pulses(ZERO6, hc10)
    off = 0.01  # ≈ 800 pulses
    # index 0: position fails before index 0's speed is looked at
    both = TrajPoint(0.0, (off,) + (0.0,) * 5, (5.0,) + (0.0,) * 5)
    r = check_start(both, commanded, hc10)
    assert r is not None
    assert r.subcode is InvalidSubcode.DATA_START_POS
    assert r.axis == 0
    # speed at index 0 fails before the position at index 1
    mixed = TrajPoint(0.0, (0.0, off) + (0.0,) * 4, (5.0,) + (0.0,) * 5)
    r = check_start(mixed, commanded, hc10)
    assert r is not None
    assert r.subcode is InvalidSubcode.DATA_SPEED
    assert r.axis == 0
    # position at index 1 fails before the speed at index 2
    later = TrajPoint(0.0, (0.0, off) + (0.0,) * 4, (0.0, 0.0, 5.0) + (0.0,) * 3)
    r = check_start(later, commanded, hc10)
    assert r is not None
    assert r.subcode is InvalidSubcode.DATA_START_POS
    assert r.axis == 1


def test_seven_axis_start_check_mixes_slot_and_ros_index() -> None:
    sia = axes_for("sia20d", "dx100")
    commanded = to_pulses((0.0,) * 7, sia)
    # The E joint (ROS 2) is in controller slot 6; a fast E velocity (ROS 2) is
    # reported at index 2 before E's own position error (slot 6) is reached.
    point = TrajPoint(0.0, (0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 9.0) + (0.0,) * 4)
    r = check_start(point, commanded, sia)
    assert r is not None
    assert r.subcode is InvalidSubcode.DATA_SPEED
    assert (r.axis, r.joint) == (2, "joint_e")
    slow = TrajPoint(0.0, point.pos, (0.0,) * 7)
    r = check_start(slow, commanded, sia)
    assert r is not None
    assert r.subcode is InvalidSubcode.DATA_START_POS
    assert (r.axis, r.joint) == (6, "joint_e")


def test_non_finite_velocities_are_refused(hc10: GroupAxes) -> None:
    for v in (float("nan"), float("inf"), 1e12):
        r = check_speed(TrajPoint(0.1, ZERO6, (v,) + (0.0,) * 5), hc10)
        assert r is not None
        assert r.subcode is InvalidSubcode.DATA_SPEED


def test_time_check() -> None:
    assert check_time(TrajPoint(14399.0, (), ())) is None
    r = check_time(TrajPoint(14400.0, (), ()))
    assert r is not None
    assert r.subcode is InvalidSubcode.DATA_TIME
    assert r.axis is None


def test_offline_raises_the_first_refusal_with_its_numbers(hc10: GroupAxes) -> None:
    points = [
        TrajPoint(0.0, ZERO6, ZERO6),
        TrajPoint(0.1, (0.1,) * 6, (2.5,) * 6),  # quirk: accepted
        TrajPoint(0.2, (0.2,) * 6, (0.0, 0.0, 0.0, 4.0, 0.0, 0.0)),  # R 4 > 3.14
        TrajPoint(15000.0, (0.2,) * 6, ZERO6),
    ]
    with pytest.raises(TrajectoryRejectedError) as info:
        interpolate(points, hc10)
    err = info.value
    assert (err.point, err.subcode, err.axis) == (2, 3013, 3)
    assert err.value == 4.0
    assert err.limit == pytest.approx(3.1416, abs=1e-4)
    assert str(err).startswith("point 2: joint_4_r")


def test_offline_refuses_a_late_point_with_3016(hc10: GroupAxes) -> None:
    points = [TrajPoint(0.0, ZERO6, ZERO6), TrajPoint(14400.5, ZERO6, ZERO6)]
    with pytest.raises(TrajectoryRejectedError) as info:
        interpolate(points, hc10)
    assert (info.value.point, info.value.subcode) == (1, 3016)


def test_overridden_ratios_keep_the_model_limit_in_rad_per_s() -> None:
    model = axes_for()
    fast = axes_for(pulses_per_unit=[100000.0] * 6)
    assert fast.max_speed == model.max_speed
    assert fast.pulses_per_unit[:6] == (100000.0,) * 6
    assert fast.max_increment[0] == int(model.max_speed[0] * 100000.0) * 4 // 1000
