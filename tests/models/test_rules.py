"""The numpy-free rules against the numpy arithmetic they must match bit for bit."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pymotoros.models import FloatMode, controller_model, robot_model
from pymotoros.models.rules import (
    GroupRules,
    f32,
    feedback_pulses,
    from_pulse,
    from_pulses,
    pulse,
)

FACTORS = st.floats(1.0, 1e7, allow_nan=False).map(f32)
COUNTS = st.integers(-(2**31), 2**31 - 1)


def _from_pulse_numpy(count: int, factor: float, mode: FloatMode) -> float:
    """The longdouble / float32 quotient the motion engine used to compute (§11)."""
    if mode is FloatMode.X87_EXTENDED:
        return float(np.float32(np.longdouble(count) / np.longdouble(factor)))
    return float(np.float32(count) / np.float32(factor))


@given(count=COUNTS, factor=FACTORS, mode=st.sampled_from(FloatMode))
def test_from_pulse_is_the_numpy_quotient(count: int, factor: float, mode: FloatMode) -> None:
    assert from_pulse(count, factor, mode) == _from_pulse_numpy(count, factor, mode)


@given(
    value=st.floats(-1e4, 1e4, allow_nan=False).map(f32),
    factor=FACTORS,
    mode=st.sampled_from(FloatMode),
)
def test_pulse_is_the_numpy_product(value: float, factor: float, mode: FloatMode) -> None:
    if mode is FloatMode.X87_EXTENDED:
        product = float(np.longdouble(value) * np.longdouble(factor))
    else:
        product = float(np.float32(value) * np.float32(factor))
    if abs(product) < 2**31:
        assert pulse(value, factor, mode) == int(product)


@given(
    pulses=st.lists(st.integers(-(2**22), 2**22), min_size=7, max_size=7),
    controller=st.sampled_from(["yrc1000", "fs100"]),
)
def test_feedback_pulses_invert_from_pulses(pulses: list[int], controller: str) -> None:
    group = robot_model("sia20d").groups[0]
    rules = GroupRules.from_model(group, controller_model(controller))
    counts = [0] * 8
    for ros, p in enumerate(pulses):
        counts[rules.ros_to_slot[ros]] = p
    assert feedback_pulses(from_pulses(counts, rules)[:7], rules) == tuple(counts)
