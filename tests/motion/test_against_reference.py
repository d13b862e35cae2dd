"""The engine against an independent rational-arithmetic model of §5.4 and §11.

``motoros_reference`` runs the step loop literally with ``fractions.Fraction`` and an
explicit float32 rounding; the engine computes whole segments with numpy longdouble or
float32. They must agree to the pulse, on both float modes, for 6- and 7-axis groups,
with segment times that do not fit the 4 ms grid.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.models import FloatMode
from pymotoros.motion import GroupAxes, TrajPoint, interpolate

from . import motoros_reference as ref
from .helpers import axes_for
from .strategies import trajectories


def reference(points: list[TrajPoint], axes: GroupAxes) -> list[tuple[int, list[int]]]:
    n = axes.num_axes
    ref_axes = ref.RefAxes(
        factors=[Fraction(axes.pulses_per_unit[axes.ros_to_slot[i]]) for i in range(n)],
        slots=list(axes.ros_to_slot[:n]),
        period_ms=axes.period_ms,
        single=axes.float_mode is FloatMode.STRICT_SINGLE,
    )
    return ref.interpolate([(p.time, p.pos, p.vel) for p in points], ref_axes)


def engine(points: list[TrajPoint], axes: GroupAxes) -> list[tuple[int, list[int]]]:
    times, incs = interpolate(points, axes, validate=False)
    return list(zip(times.tolist(), incs.tolist(), strict=True))


@settings(max_examples=60, deadline=None)
@given(trajectories(), st.sampled_from(["yrc1000", "fs100"]))
def test_six_axes_match_the_reference(points: list[TrajPoint], controller: str) -> None:
    axes = axes_for("hc10", controller)
    assert engine(points, axes) == reference(points, axes)


@settings(max_examples=30, deadline=None)
@given(trajectories(n_axes=7), st.sampled_from(["dx100", "fs100"]))
def test_seven_axes_match_the_reference(points: list[TrajPoint], controller: str) -> None:
    axes = axes_for("sia20d", controller)
    assert engine(points, axes) == reference(points, axes)


@settings(max_examples=30, deadline=None)
@given(
    trajectories(),
    st.sampled_from(["yrc1000", "fs100"]),
    st.lists(st.floats(1000.0, 400000.0), min_size=6, max_size=6),
)
def test_any_pulse_ratio_matches_the_reference(
    points: list[TrajPoint], controller: str, ratios: list[float]
) -> None:
    axes = axes_for("hc10", controller, pulses_per_unit=ratios)
    assert engine(points, axes) == reference(points, axes)


@pytest.mark.parametrize(("controller", "last"), [("yrc1000", 4), ("fs100", 5)])
def test_a_hand_checked_25ms_segment(controller: str, last: int) -> None:
    """One axis from 0 to 0.01 rad in 25 ms, at rest at both ends, ratio 100000 pulses/rad.

    The cubic is then 0.01·(3s² − 2s³) with s = t / 25 ms: at 4, 8 … 24 ms that is
    68.608, 241.664, 470.016, 704.512, 896 (a hair under in float32), 995.328 pulses.
    The end is 0.01 rad: 999.99997 pulses truncated to 999 on x87, 1000 on FS100.
    """
    axes = axes_for("hc10", controller, pulses_per_unit=[100000.0] * 6)
    points = [
        TrajPoint(0.0, (0.0,) * 6, (0.0,) * 6),
        TrajPoint(0.0255, (0.01,) + (0.0,) * 5, (0.0,) * 6),
    ]
    times, incs = interpolate(points, axes)
    assert times.tolist() == [4, 8, 12, 16, 20, 24, 25]
    assert incs[:, 0].tolist() == [68, 173, 229, 234, 191, 100, last]
    assert np.all(incs[:, 1:] == 0)
    assert engine(points, axes) == reference(points, axes)
