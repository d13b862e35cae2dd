"""Cases built so that only the x87 80-bit evaluation gives MotoROS's pulse (§11).

Random trajectories almost never separate extended precision from float64 (the
reference says "off by one pulse now and then"); this case does, on purpose:
x0 = 1 + 2⁻²³ and v0·τ = 3·2⁻²⁴ + 5.1·10⁻¹⁷ put x0 + v0·τ a hair above a float32
midpoint. An 80-bit register keeps the hair, float64 loses it and rounds the tie to
even, one float32 step (one pulse at 2²³ pulses/rad) lower.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.models import FloatMode
from pymotoros.motion import TrajPoint, interpolate, numerics
from pymotoros.motion.numerics import LD, positions, pulses

from .helpers import axes_for
from .motoros_reference import round_f32
from .strategies import trajectories
from .test_tick_engine import queued_by_ticks

X0 = np.float32(1 + 2**-23)
V0 = np.float32(15123692 * 2.0**-42)  # exactly representable
TAU = (LD(52) / LD(1000)).astype(np.float32)  # τ of the step 52 ms into a segment
ZERO = np.zeros(1, dtype=np.float32)
FACTOR = np.array([2.0**23], dtype=np.float32)


def test_x87_keeps_what_float64_loses() -> None:
    pos = positions(
        np.array([X0]), np.array([V0]), ZERO, ZERO, np.array([[TAU]]), FloatMode.X87_EXTENDED
    )
    exact = round_f32(Fraction(float(X0)) + Fraction(float(V0)) * Fraction(float(TAU)))
    float64 = np.float32(np.float64(X0) + np.float64(V0) * np.float64(TAU))
    assert float(pos[0, 0]) == float(exact) == 1 + 3 * 2**-23
    assert float(float64) == 1 + 2 * 2**-23  # what a float64 engine would store
    assert pulses(pos, FACTOR, FloatMode.X87_EXTENDED).tolist() == [[2**23 + 3]]


def test_fs100_rounds_the_product_first() -> None:
    pos = positions(
        np.array([X0]), np.array([V0]), ZERO, ZERO, np.array([[TAU]]), FloatMode.STRICT_SINGLE
    )
    product = round_f32(Fraction(float(V0)) * Fraction(float(TAU)))
    assert float(pos[0, 0]) == float(round_f32(Fraction(float(X0)) + product))


@settings(max_examples=25, deadline=None)
@given(trajectories(durations=st.integers(1, 400).map(lambda k: k / 1000)))
def test_the_checked_float64_paths_equal_the_longdouble_fallback(points: list[TrajPoint]) -> None:
    """With an absurd safety factor every value takes the longdouble fallback; the
    results must not change (both in the tick engine and the offline engine)."""
    axes = axes_for("hc10", "yrc1000")
    normal = interpolate(points, axes, validate=False)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(numerics, "RISK_FACTOR", 1e300)
        mp.setattr(numerics, "COEF_RISK_FACTOR", 1e300)
        assert numerics.coefficients_x87_scalar([0.1], [0.2], [0.3], [0.4], 0.1) is None
        forced = interpolate(points, axes, validate=False)
        ticks = queued_by_ticks(points, axes)
    assert ticks == list(zip(normal[0].tolist(), normal[1].tolist(), strict=True))
    assert np.array_equal(normal[0], forced[0])
    assert np.array_equal(normal[1], forced[1])
