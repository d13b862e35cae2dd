"""The cross-segment kernel and the small-segment path against the per-segment path.

``batch.batch_increments`` (the offline engine) and ``batch.queued_targets`` (the tick
engine's queued segments) compute many segments at once; ``GroupInterpolator``
computes a lone segment of a few steps in plain Python floats. Both must give exactly what
``one_segment.compute_segment`` gives one segment at a time, with the grid carried from
segment to segment as the real task carries it (leftover, its quirk, dropped points).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.motion import GroupAxes, TrajPoint, batch, interpolate, numerics
from pymotoros.motion.constants import SLOTS
from pymotoros.motion.numerics import LD, position_bound
from pymotoros.motion.one_segment import compute_segment
from pymotoros.motion.points import GroupPoint
from pymotoros.motion.segment import plan_grid

from .helpers import axes_for
from .strategies import trajectories
from .test_tick_engine import queued_by_ticks

CELLS = [("hc10", "yrc1000"), ("hc10", "fs100"), ("sia20d", "dx100"), ("sia20d", "fs100")]

# Dense points: most segments have no step or a few steps besides the last one; the
# quirk (a leftover-sized first step landing exactly on the end) and dropped points
# come up often.
DENSE = st.one_of(
    st.integers(1, 40).map(lambda k: k / 1000 + 0.0005),
    st.integers(1, 12).map(lambda k: k / 1000),
    st.sampled_from([0.0, -0.002, 0.1]),
)


def per_segment(points: list[TrajPoint], axes: GroupAxes) -> list[tuple[int, list[int]]]:
    """The literal task: one compute_segment per accepted point, state carried over."""
    mode = axes.float_mode
    current = GroupPoint.from_traj(points[0], mode)
    leftover = 0
    prev = tuple(
        numerics.pulse(current.pos[r], axes.pulses_per_unit[s], mode) if r < axes.num_axes else 0
        for s, r in enumerate(axes.slot_to_ros)
    )
    out: list[tuple[int, list[int]]] = []
    for point in points[1:]:
        end = GroupPoint.from_traj(point, mode)
        segment = compute_segment(current, end, leftover, prev, 0, axes)
        if segment is None:  # not after the current time: dropped
            continue
        for entry in segment.entries:
            out.append((entry.time_ms, [entry.pulses[s] for s in axes.axis_slots]))
        grid = plan_grid(current.time_ms, end.time_ms, leftover, axes.period_ms)
        assert grid == segment.grid
        leftover = grid.leftover_ms
        last = segment.targets[-1].tolist()
        merged = list(prev)
        for slot, value in zip(axes.axis_slots, last, strict=True):
            merged[slot] = value
        prev = tuple(merged)
        current = end
    return out


def fit(points: list[TrajPoint], axes: GroupAxes) -> list[TrajPoint]:
    n = axes.num_axes
    return [
        TrajPoint(
            p.time, p.pos[:n] + (0.1,) * (n - len(p.pos)), p.vel[:n] + (0.0,) * (n - len(p.vel))
        )
        for p in points
    ]


@settings(max_examples=80, deadline=None)
@given(
    st.one_of(trajectories(max_points=12, durations=DENSE), trajectories(max_points=8)),
    st.sampled_from(CELLS),
    st.sampled_from([(1, 1), (3, 2), (2048, 1024)]),
)
def test_the_cross_segment_kernel_equals_the_per_segment_path(
    points: list[TrajPoint], cell: tuple[str, str], chunks: tuple[int, int]
) -> None:
    axes = axes_for(*cell)
    points = fit(points, axes)
    with pytest.MonkeyPatch.context() as mp:
        # Tiny blocks exercise every block boundary of the kernel.
        mp.setattr(batch, "CHUNK", chunks[0])
        mp.setattr(batch, "SEGMENT_CHUNK", chunks[1])
        times, incs = interpolate(points, axes, validate=False)
    offline = list(zip(times.tolist(), incs.tolist(), strict=True))
    assert offline == per_segment(points, axes)


@settings(max_examples=60, deadline=None)
@given(trajectories(max_points=12, durations=DENSE), st.sampled_from(CELLS))
def test_lone_small_segments_equal_the_kernel(
    points: list[TrajPoint], cell: tuple[str, str]
) -> None:
    """Streamed one point at a time, each segment is computed on its own (the plain
    Python path for a few steps, the end point alone for none)."""
    axes = axes_for(*cell)
    points = fit(points, axes)
    times, incs = interpolate(points, axes, validate=False)
    assert queued_by_ticks(points, axes) == list(zip(times.tolist(), incs.tolist(), strict=True))


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(-3.0, 3.0, width=32), min_size=4, max_size=4),
    st.integers(1, 40),
    st.integers(0, 39),
)
def test_scalar_positions_equal_the_numpy_check(
    values: list[float], t_ms: int, tau_ms: int
) -> None:
    x0, v0, h1, a2 = ([v] for v in values)
    t = float(np.float32(t_ms / 1000))
    tau = float(np.float32(min(tau_ms, t_ms) / 1000))
    scalar = numerics.positions_x87_scalar(x0, v0, h1, a2, [tau], t)
    arrays = [np.array([v], dtype=np.float64) for v in values]
    bound = position_bound(*arrays, t)
    checked = numerics.positions_x87_checked(*arrays, np.array([[tau]]), bound)
    if scalar is not None:
        assert scalar == [tuple(checked[0].tolist())]


def test_the_coefficient_error_bound_holds_on_nearly_cancelling_terms() -> None:
    """COEF_RISK_FACTOR rests on |float64 − x87| < 5.001 × 2⁻⁵³ × (|term 1| + |term 2|)
    before the float32 store. Smooth trajectories sampled densely make the two terms
    of each coefficient nearly cancel, where a wrong bound would show."""
    rng = np.random.default_rng(20261122)
    worst = 0.0
    for spacing in (0.001, 0.004, 0.02, 0.1):
        t = np.arange(0.0, 30.0, spacing)
        freq = rng.uniform(0.02, 0.5, SLOTS)
        phase = rng.uniform(0, 6.3, SLOTS)
        amp = rng.uniform(0.1, 3.0, SLOTS)
        pos = (amp * np.sin(freq * t[:, None] + phase)).astype(np.float32).astype(np.float64)
        vel = (amp * freq * np.cos(freq * t[:, None] + phase)).astype(np.float32)
        vel = vel.astype(np.float64)
        dur = np.float32(spacing)
        x0, x1, v0, v1 = pos[:-1], pos[1:], vel[:-1], vel[1:]
        d = float(dur)
        tt, ttt = d * d, d * d * d
        terms64 = (
            ((x1 - x0) * 6) / tt,
            ((v1 + 2 * v0) * -2) / d,
            ((x1 - x0) * -12) / ttt,
            ((v1 + v0) * 6) / tt,
        )
        lx0, lx1, lv0, lv1 = (a.astype(LD) for a in (x0, x1, v0, v1))
        ld, ltt = LD(d), LD(d) * LD(d)
        a1_ld = ((lx1 - lx0) * 6) / ltt + ((lv1 + 2 * lv0) * -2) / ld
        a2_ld = ((lx1 - lx0) * -12) / (ltt * ld) + ((lv1 + lv0) * 6) / ltt
        for (p, q), exact in (((0, 1), a1_ld), ((2, 3), a2_ld)):
            f = terms64[p] + terms64[q]
            size = np.abs(terms64[p]) + np.abs(terms64[q])
            gap = np.abs(f.astype(LD) - exact).astype(np.float64)
            ratio = np.where(size > 0, gap / (size * 2.0**-53), 0.0)
            worst = max(worst, float(ratio.max()))
    assert worst < 5.001
    assert 2 * worst < numerics.COEF_RISK_FACTOR


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-3.0, 3.0, width=32), min_size=72, max_size=72),
    st.lists(st.integers(1, 300), min_size=3, max_size=3),
)
def test_the_scalar_coefficient_redo_equals_the_array_redo(
    values: list[float], lengths_ms: list[int]
) -> None:
    rows = np.array(values, dtype=np.float64).reshape(4, 3, 6)
    t = np.array([[float(np.float32(k / 1000))] for k in lengths_ms])
    with pytest.MonkeyPatch.context() as mp, np.errstate(over="ignore"):
        mp.setattr(numerics, "COEF_RISK_FACTOR", 1e300)  # every value is redone
        mp.setattr(numerics, "SCALAR_REDO", 10**6)
        one_by_one = numerics.coefficients_x87_checked(rows, t)
        mp.setattr(numerics, "SCALAR_REDO", 0)
        whole = numerics.coefficients_x87_checked(rows, t)
    assert np.array_equal(one_by_one, whole)
