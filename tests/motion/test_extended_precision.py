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

from pymotoros.models import FloatMode
from pymotoros.motion.numerics import LD, positions, pulses

from .motoros_reference import round_f32

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
