"""The known numbers of reference §11, both float modes."""

from __future__ import annotations

import numpy as np
import pytest

from pymotoros.models import FloatMode
from pymotoros.motion import to_pulses
from pymotoros.motion.constants import INT32_MAX, INT32_MIN
from pymotoros.motion.numerics import c_int, c_int_array, f32, pulse, pulses, seconds_to_ms

from .helpers import axes_for

X87 = FloatMode.X87_EXTENDED
FS100 = FloatMode.STRICT_SINGLE


@pytest.mark.parametrize(
    ("seconds", "mode", "ms"),
    [
        (0.7, X87, 699),  # 0.699999988 as float32, truncated from the exact product
        (0.7, FS100, 700),  # the product is rounded to float32 first
        (0.025, X87, 25),
        (1.0, X87, 1000),
        (0.0, X87, 0),
        (-0.0015, X87, -1),  # truncation toward zero, negative times are allowed
        (14399.999, X87, 14399999),
    ],
)
def test_seconds_to_ms(seconds: float, mode: FloatMode, ms: int) -> None:
    assert seconds_to_ms(seconds, mode) == ms


@pytest.mark.parametrize(
    ("value", "mode", "expected"),
    [(0.7, X87, 69999), (-0.7, X87, -69999), (0.7, FS100, 70000), (-0.7, FS100, -70000)],
)
def test_pulse_truncation(value: float, mode: FloatMode, expected: int) -> None:
    assert pulse(f32(value), 100000.0, mode) == expected
    arr = pulses(np.array([[value]], dtype=np.float32), np.array([1e5], dtype=np.float32), mode)
    assert arr.tolist() == [[expected]]


@pytest.mark.parametrize(("controller", "expected"), [("yrc1000", 69999), ("fs100", 70000)])
def test_to_pulses_with_overridden_ratio(controller: str, expected: int) -> None:
    axes = axes_for(controller=controller, pulses_per_unit=[100000.0] * 6)
    assert to_pulses((0.7,) * 6, axes) == (expected,) * 6 + (0, 0)
    assert to_pulses((-0.7,), axes)[0] == -expected


def test_out_of_range_conversions_follow_each_instruction_set() -> None:
    assert c_int(3e9, X87) == INT32_MIN  # x87 "integer indefinite"
    assert c_int(float("nan"), X87) == INT32_MIN
    assert c_int(3e9, FS100) == INT32_MAX  # PowerPC saturates
    assert c_int(-3e9, FS100) == INT32_MIN
    assert c_int(float("nan"), FS100) == 0
    got = c_int_array(np.array([1.9, -1.9, 3e9, -3e9]), FS100).tolist()
    assert got == [1, -1, INT32_MAX, INT32_MIN]
    assert c_int_array(np.array([3e9, 2.5]), X87).tolist() == [INT32_MIN, 2]
