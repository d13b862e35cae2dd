"""The fused plain-Python kernel of a lone small segment gives the x87's float32 values.

:func:`~pymotoros.motion.numerics.small_segment_x87` computes a segment's coefficients
and positions in float64 and keeps them only where its error bounds prove them equal to
the x87's; otherwise it returns None and the caller takes the longdouble path. Here its
results are compared with the longdouble (x87) computation itself, on random values and
on dense smooth trajectories (where the coefficient terms nearly cancel), and the
tick engine is compared with the reference route (``tests/oracles/interpolation.py``:
the numpy kernels for every segment) and with the two-pass form it falls back to.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oracles.interpolation import all_at_once
from pymotoros.models.rules import f32
from pymotoros.motion import TrajPoint, interpolate, interpolator, numerics

from .helpers import axes_for, x87_positions
from .strategies import trajectories
from .test_batch import fit
from .test_tick_engine import queued_by_ticks

F32 = st.floats(-3.0, 3.0, width=32)


@settings(max_examples=300, deadline=None)
@given(
    st.integers(1, 8).flatmap(lambda n: st.lists(F32, min_size=4 * n, max_size=4 * n)),
    st.integers(2, 40),
    st.lists(st.integers(1, 39), min_size=1, max_size=3),
)
def test_fused_kernel_equals_the_x87(values: list[float], t_ms: int, tau_ms: list[int]) -> None:
    n = len(values) // 4
    x0, v0, x1, v1 = (values[k * n : (k + 1) * n] for k in range(4))
    t = f32(t_ms / 1000)
    taus = [f32(min(k, t_ms - 1) / 1000) for k in tau_ms]
    fused = numerics.small_segment_x87(x0, v0, x1, v1, t, taus)
    if fused is not None:
        assert fused == x87_positions(x0, v0, x1, v1, t, taus)


def test_fused_kernel_on_dense_smooth_motion() -> None:
    """Points every 1–8 ms on slow sines: the coefficient terms nearly cancel, where a
    wrong error bound would show. Most segments must take the fused path (else
    this test would prove nothing) and every result must be the x87's."""
    rng = np.random.default_rng(20261124)
    taken = total = 0
    for spacing_ms in (1, 3, 4, 5, 8):
        times = np.arange(0, 2000, spacing_ms) / 1000
        freq = rng.uniform(0.05, 0.5, 6)
        amp = rng.uniform(0.2, 2.0, 6)
        pos = [[f32(a * math.sin(w * s)) for a, w in zip(amp, freq, strict=True)] for s in times]
        vel = [
            [f32(a * w * math.cos(w * s)) for a, w in zip(amp, freq, strict=True)] for s in times
        ]
        for k in range(len(times) - 1):
            t = f32(spacing_ms / 1000)
            taus = [f32(j / 1000) for j in range(1, spacing_ms, 4)] or [f32(0.0005)]
            fused = numerics.small_segment_x87(pos[k], vel[k], pos[k + 1], vel[k + 1], t, taus)
            total += 1
            if fused is not None:
                taken += 1
                assert fused == x87_positions(pos[k], vel[k], pos[k + 1], vel[k + 1], t, taus)
    assert taken > total // 2, f"only {taken} of {total} segments took the fused path"


@pytest.mark.parametrize("bad", [math.nan, math.inf, 1e31], ids=["nan", "inf", "huge"])
def test_fused_kernel_gives_up_on_values_it_cannot_vouch_for(bad: float) -> None:
    """Non-finite values, or values beyond float32: None, the longdouble path decides."""
    x0, v0, x1, v1 = [0.5, bad], [0.0, 0.0], [0.5, 2 * bad], [0.0, 0.0]
    assert numerics.small_segment_x87(x0, v0, x1, v1, f32(0.004), [f32(0.002)]) is None


def test_fused_kernel_on_tiny_values() -> None:
    """Values in float32's subnormal range round as the x87 stores them."""
    x0, v0, x1, v1 = [0.5, 1e-40], [0.0, 3e-41], [0.5, 2e-40], [0.0, -1e-41]
    t, taus = f32(0.005), [f32(0.001), f32(0.003)]
    fused = numerics.small_segment_x87(x0, v0, x1, v1, t, taus)
    assert fused is not None
    assert fused == x87_positions(x0, v0, x1, v1, t, taus)
    assert [math.copysign(1.0, v) for row in fused for v in row] == [
        math.copysign(1.0, v) for row in x87_positions(x0, v0, x1, v1, t, taus) for v in row
    ]


@settings(max_examples=40, deadline=None)
@given(
    trajectories(max_points=16, durations=st.integers(1, 12).map(lambda k: k / 1000)),
    st.sampled_from([("hc10", "yrc1000"), ("sia20d", "dx100"), ("hc10", "fs100")]),
)
def test_tick_engine_with_and_without_the_plain_python_paths(
    points: list[TrajPoint], cell: tuple[str, str]
) -> None:
    """Dense points streamed one at a time: the same entries from the fused kernel, the
    two-pass form it falls back to (the fused kernel made to give up) and the numpy
    kernels (the reference route), and the offline engine agrees."""
    axes = axes_for(*cell)
    points = fit(points, axes)
    results = [queued_by_ticks(points, axes)]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(interpolator, "small_segment_x87", lambda *_args: None)
        results.append(queued_by_ticks(points, axes))
    with all_at_once():
        results.append(queued_by_ticks(points, axes))
    times, incs = interpolate(points, axes, validate=False)
    offline = list(zip(times.tolist(), incs.tolist(), strict=True))
    assert results == [offline] * 3


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.floats(-3.0, 3.0, width=32),
            st.sampled_from([3e4, -3e4, 1e6, math.nan, math.inf]),  # pulses beyond int32
        ),
        min_size=6,
        max_size=6,
    ),
    st.integers(1, 12),
)
def test_end_point_only_segments_with_and_without_the_plain_python_path(
    odd: list[float], where: int
) -> None:
    """Points exactly one period apart give segments that are only their end point
    (:meth:`GroupInterpolator._store_end_x87` on the x87 with slots in ROS order):
    the same entries as the numpy kernels (the reference route), also when a product
    leaves the int32 range or is not a number (the general conversion then decides)."""
    axes = axes_for("hc10", "yrc1000")
    points = [
        TrajPoint(k * 0.004 + 0.0005, tuple(0.01 * k * (j + 1) for j in range(6)), (0.0,) * 6)
        for k in range(14)
    ]
    points[where] = TrajPoint(points[where].time, tuple(odd), (0.0,) * 6)
    results = [queued_by_ticks(points, axes)]
    with all_at_once():
        results.append(queued_by_ticks(points, axes))
    assert results[0] == results[1]
    assert len(results[0]) == len(points) - 1  # one entry per segment: the end point
