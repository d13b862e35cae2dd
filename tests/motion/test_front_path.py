"""The queue's oldest segment computed alone gives the batch's pulses, bit for bit.

When IncMove reaches a queued segment of :data:`~pymotoros.motion.interpolator.
FRONT_MIN_ENTRIES` entries or more, the tick engine computes it alone with
:func:`~pymotoros.motion.batch.segment_targets` (plain-Python coefficients, one position
kernel) instead of every queued segment with :func:`~pymotoros.motion.batch.
queued_targets`. Here the two are compared on single segments (random values, values
whose positions land next to a float32 midpoint so that the longdouble fallback decides,
subnormal and large values, pieces far into a long segment, zero and one step), against
a long-double model of the x87, and through the tick engine taking entries as IncMove
does, against the reference route (every segment through the batch kernel,
``tests/oracles/interpolation.py``) and the offline engine.
"""

from __future__ import annotations

import math
from contextlib import nullcontext

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from oracles.interpolation import all_at_once
from pymotoros.models import FloatMode
from pymotoros.models.rules import f32
from pymotoros.motion import (
    GroupInterpolator,
    TrajPoint,
    batch,
    interpolate,
    interpolator,
    numerics,
    to_pulses,
)
from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.constants import QUEUE_SIZE
from pymotoros.motion.points import GroupPoint

from .helpers import axes_for, x87_positions
from .strategies import trajectories
from .test_batch import CELLS, fit

PERIOD_MS = 4
"""The interpolation period of every cell here (ms)."""
TAME = 1e14
"""Largest magnitude drawn: inside GroupPoint.tame's limit (1e15 over all values)."""


def float32s(limit: float) -> st.SearchStrategy[float]:
    bound = f32(limit)
    return st.floats(-bound, bound, width=32, allow_nan=False, allow_infinity=False)


VALUES = st.one_of(
    float32s(3.5),
    float32s(1e-37),  # subnormal and tiny
    float32s(TAME / 64),
    st.sampled_from([0.0, -0.0, 1.0, -2.5]),
)


def single_segment(
    rows: list[list[float]],
    length_ms: int,
    lead_ms: int,
    steps: int,
    with_end: bool,
    axes: GroupAxes,
) -> tuple[list[int], list[list[int]]]:
    """What the batch path computes for this one segment (times, targets)."""
    array = np.array(rows, dtype=np.float32)[:, None]
    grid = (0, length_ms, lead_ms, steps, with_end)
    times, targets = batch.queued_targets(array, [grid], axes)
    return times, targets.tolist()


def x87_model(
    rows: list[list[float]],
    length_ms: int,
    lead_ms: int,
    steps: int,
    with_end: bool,
    axes: GroupAxes,
) -> list[list[int]]:
    """The x87 targets computed in longdouble throughout (coefficients, positions) and
    truncated with the scalar pulse rule: no float64 shortcut anywhere."""
    x0, v0, x1, v1 = rows
    duration = f32(length_ms / 1000)
    out: list[list[float]] = []
    if steps:
        taus = [f32((lead_ms + PERIOD_MS * k) / 1000) for k in range(steps)]
        out = [list(row) for row in x87_positions(x0, v0, x1, v1, duration, taus)]
    if with_end:
        out.append(list(x1))
    factors = axes.factors_ros_list
    targets = [
        [numerics.pulse(x, f, axes.float_mode) for x, f in zip(row, factors, strict=True)]
        for row in out
    ]
    return [[row[j] for j in axes.columns_list] for row in targets]


@st.composite
def segments(draw: st.DrawFn) -> tuple[int, int, int, bool]:
    """(length ms, first step's offset, steps, with end): a whole segment, or a piece of
    one far into it (its first step millions of ms after the start), zero to 60 steps
    or a whole 200-entry piece."""
    steps = draw(st.one_of(st.integers(0, 3), st.integers(4, 60), st.just(QUEUE_SIZE)))
    leftover = draw(st.integers(1, PERIOD_MS))
    skipped = draw(st.one_of(st.just(0), st.integers(1, 3_600_000)))
    lead = leftover + PERIOD_MS * skipped
    with_end = draw(st.booleans())
    tail = draw(st.integers(1, PERIOD_MS)) if with_end else draw(st.integers(1, 10_000_000))
    return lead + PERIOD_MS * max(steps - 1, 0) + tail, lead, steps, with_end


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(CELLS), st.data())
def test_one_segment_equals_the_batch_path(cell: tuple[str, str], data: st.DataObject) -> None:
    axes = axes_for(*cell)
    n = axes.num_axes
    rows = [data.draw(st.lists(VALUES, min_size=n, max_size=n)) for _ in range(4)]
    length, lead, steps, with_end = data.draw(segments())
    targets = batch.segment_targets(
        (rows[0], rows[1]), (rows[2], rows[3]), length, lead, steps, with_end, axes
    )
    times, expected = single_segment(rows, length, lead, steps, with_end, axes)
    assert targets.tolist() == expected
    assert len(times) == steps + with_end
    if axes.float_mode is FloatMode.X87_EXTENDED:
        assert targets.tolist() == x87_model(rows, length, lead, steps, with_end, axes)


def test_positions_next_to_a_float32_midpoint_take_the_longdouble_fallback(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Linear motion aimed at the midpoint between two float32 values: the coefficients
    nearly vanish and the float64 positions land within the error bound of the
    midpoint, where only the longdouble computation can say how the x87 rounds. The
    fallback must be taken (else this test proves nothing) and every target must be the
    batch path's and the long-double model's."""
    fallbacks = [0]
    real = batch.positions_x87

    def counting(*args: np.ndarray) -> np.ndarray:
        fallbacks[0] += args[0].size
        return real(*args)

    monkeypatch.setattr(batch, "positions_x87", counting)  # segment_targets' fallback only
    axes = axes_for("hc10", "yrc1000")
    rng = np.random.default_rng(20261124)
    for _ in range(300):
        length = int(rng.integers(20, 200)) * PERIOD_MS + int(rng.integers(1, PERIOD_MS + 1))
        t = f32(length / 1000)
        tau = f32(int(rng.integers(1, length // PERIOD_MS)) * PERIOD_MS / 1000)
        x0 = [f32(v) for v in rng.uniform(-3, 3, 6)]
        # v0 such that x0 + v0·τ is the midpoint above x0 (half a float32 ulp away)
        v0 = [f32(float(np.spacing(np.float32(x))) / 2 / tau) for x in x0]
        x1 = [f32(x + v * t) for x, v in zip(x0, v0, strict=True)]
        rows = [x0, v0, x1, list(v0)]
        steps = (length - 1) // PERIOD_MS
        got = batch.segment_targets((x0, v0), (x1, v0), length, PERIOD_MS, steps, True, axes)
        assert got.tolist() == single_segment(rows, length, PERIOD_MS, steps, True, axes)[1]
        assert got.tolist() == x87_model(rows, length, PERIOD_MS, steps, True, axes)
    assert fallbacks[0] > 0, "no position needed the longdouble fallback"


def take_like_incmove(
    points: list[TrajPoint], axes: GroupAxes, *, front: bool
) -> tuple[list[tuple[int, list[int]]], int]:
    """Stream the points (the next one as soon as not BUSY) and take one entry per tick
    through ``queue.due()`` as IncMove does; (every entry, segments computed alone).
    ``front=False``: the reference route (``tests/oracles/interpolation.py``)."""
    alone = [0]
    real = interpolator.segment_targets

    def counting(*args: object, **kwargs: object) -> object:
        alone[0] += 1
        return real(*args, **kwargs)  # type: ignore[arg-type]

    with pytest.MonkeyPatch.context() as mp, (nullcontext() if front else all_at_once()):
        mp.setattr(interpolator, "segment_targets", counting)
        g = GroupInterpolator(axes)
        g.start(points[0], to_pulses(points[0].pos, axes))
        rest = list(points[1:])
        seen: list[tuple[int, list[int]]] = []
        for _ in range(200_000):
            if rest and not g.pending:
                g.set_pending(rest.pop(0))
            g.fill(True)
            entries = g.queue.due()
            if entries:
                entry = entries.popleft()
                seen.append((entry.time_ms, [entry.pulses[s] for s in axes.axis_slots]))
            elif not g.queue.count and not rest and not g.pending:
                return seen, alone[0]
    raise AssertionError("did not finish")


SPARSE = st.one_of(
    st.integers(80, 1200).map(lambda k: k / 1000),  # 20 entries and more: alone
    st.integers(1, 79).map(lambda k: k / 1000),  # fewer: with the others
    st.sampled_from([0.1, 0.0, -0.002]),  # 100 ms, dropped points
)


@settings(max_examples=40, deadline=None)
@given(trajectories(max_points=10, durations=SPARSE), st.sampled_from(CELLS))
def test_tick_engine_with_and_without_the_front_path(
    points: list[TrajPoint], cell: tuple[str, str]
) -> None:
    axes = axes_for(*cell)
    points = fit(points, axes)
    front, _ = take_like_incmove(points, axes, front=True)
    together, none = take_like_incmove(points, axes, front=False)
    assert none == 0
    assert front == together
    times, incs = interpolate(points, axes, validate=False)
    assert front == list(zip(times.tolist(), incs.tolist(), strict=True))


def test_the_front_path_is_taken_for_long_segments_only() -> None:
    """Points 100 ms apart: every segment computed alone; 20 ms apart: none (the batch
    is cheaper per entry, interpolator.FRONT_MIN_ENTRIES)."""
    axes = axes_for("hc10", "yrc1000")
    for spacing, expect_alone in ((0.1, True), (0.02, False)):
        points = [
            TrajPoint(
                k * spacing, tuple(0.3 * math.sin(k * spacing + j) for j in range(6)), (0.0,) * 6
            )
            for k in range(30)
        ]
        _, alone = take_like_incmove(points, axes, front=True)
        assert (alone >= len(points) - 2) if expect_alone else alone == 0, (spacing, alone)


def test_points_that_are_not_tame_take_the_general_kernel() -> None:
    """A huge position (not tame) in a long segment: computed alone by the general
    kernel, the same entries as the batch path."""
    axes = axes_for("hc10", "yrc1000")
    points = [TrajPoint(k * 0.1, (0.1 * k,) * 6, (0.0,) * 6) for k in range(6)]
    points[3] = TrajPoint(0.3, (1e31, 0.2, 0.3, math.inf, math.nan, 0.0), (0.0,) * 6)
    assert not GroupPoint.from_traj(points[3], axes.float_mode).tame
    front, alone = take_like_incmove(points, axes, front=True)
    together, _ = take_like_incmove(points, axes, front=False)
    assert front == together
    # five segments; the two on either side of the odd point took the general kernel
    assert alone == 3


def test_coefficients_that_nearly_vanish_are_the_x87s(monkeypatch: pytest.MonkeyPatch) -> None:
    """Uniform motion (x1 = x0 + v·T, v1 = v0): both terms of each coefficient are large
    and cancel to rounding noise, so a float64 coefficient is often within its error
    bound of a float32 midpoint and sometimes rounds differently from the x87's. The
    coefficients the segment's position kernel gets must be the x87's (a rounding
    noise coefficient barely moves a pulse, so the targets alone would hardly show a
    wrong one), and its targets the batch path's and the long-double model's. The data
    must contain coefficients that float64 rounds differently and coefficients the
    interval check cannot vouch for (else this test proves nothing)."""
    axes = axes_for("hc10", "yrc1000")
    rng = np.random.default_rng(20261125)
    given_terms: list[tuple[list[float], list[float]]] = []
    real = batch.positions_x87_interval

    def spying(*args: np.ndarray) -> np.ndarray:
        given_terms.append((args[0][2].tolist(), args[0][3].tolist()))
        return real(*args)

    monkeypatch.setattr(batch, "positions_x87_interval", spying)
    differ = unsure = 0
    for _ in range(200):
        length = int(rng.integers(20, 250)) * PERIOD_MS + int(rng.integers(1, PERIOD_MS + 1))
        t = f32(length / 1000)
        x0 = [f32(v) for v in rng.choice([0.0, 0.25, -1.5], 6) + rng.uniform(-1e-3, 1e-3, 6)]
        v0 = [f32(v) for v in rng.uniform(-3, 3, 6)]
        x1 = [f32(x + v * t) for x, v in zip(x0, v0, strict=True)]
        rows = [x0, v0, x1, list(v0)]
        tt = t * t
        plain = [
            f32((6 * (b - a)) / tt - (2 * (v + 2 * v)) / t)
            for a, b, v in zip(x0, x1, v0, strict=True)
        ] + [
            f32((-12 * (b - a)) / (tt * t) + (6 * (v + v)) / tt)
            for a, b, v in zip(x0, x1, v0, strict=True)
        ]
        exact = numerics.coefficients_x87_exact(x0, v0, x1, v0, t)
        differ += plain != exact
        unsure += numerics.coefficients_x87_interval(x0, v0, x1, v0, t) is None
        steps = (length - 1) // PERIOD_MS
        got = batch.segment_targets((x0, v0), (x1, v0), length, PERIOD_MS, steps, True, axes)
        assert given_terms[-1] == ([c / 2 for c in exact[:6]], exact[6:])
        assert got.tolist() == single_segment(rows, length, PERIOD_MS, steps, True, axes)[1]
        assert got.tolist() == x87_model(rows, length, PERIOD_MS, steps, True, axes)
    assert differ > 0, "no float64 coefficient rounded differently from the x87's"
    assert unsure > 0, "the interval check vouched for every coefficient"


@settings(max_examples=300, deadline=None)
@given(
    st.integers(1, 8).flatmap(lambda n: st.lists(VALUES, min_size=4 * n, max_size=4 * n)),
    st.integers(1, 20_000),
)
def test_interval_coefficients_are_the_x87s(values: list[float], t_ms: int) -> None:
    """:func:`coefficients_x87_interval`, whenever it answers, gives the long-double
    coefficients, and agrees with the array check the batch path uses."""
    n = len(values) // 4
    x0, v0, x1, v1 = (values[k * n : (k + 1) * n] for k in range(4))
    t = f32(t_ms / 1000)
    got = numerics.coefficients_x87_interval(x0, v0, x1, v1, t)
    if got is None:
        return
    assert list(got) == numerics.coefficients_x87_exact(x0, v0, x1, v1, t)
    rows = np.array([x0, v0, x1, v1], dtype=np.float64)[:, None]
    checked = numerics.coefficients_x87_checked(rows, np.array([[t]])).ravel().tolist()
    assert list(got) == checked


def test_pieces_deep_into_a_long_segment_are_not_memoised() -> None:
    """Each later piece of a 14,399 s segment has its own first-step offset: the τ memo
    keeps only whole segments' grids, so a client cannot fill it with them."""
    axes = axes_for("hc10", "yrc1000")
    rows = ([0.0] * 6, [0.0] * 6), ([0.5] * 6, [0.0] * 6)
    batch._tau_column.cache_clear()
    for piece in range(1, 50):
        lead = 4 + PERIOD_MS * QUEUE_SIZE * piece
        batch.segment_targets(*rows, 14_399_000, lead, QUEUE_SIZE, False, axes)
    assert batch._tau_column.cache_info().currsize == 0
    batch.segment_targets(*rows, 100, 4, 24, True, axes)
    batch.segment_targets(*rows, 100, 4, 24, True, axes)
    assert batch._tau_column.cache_info().currsize == 1
    assert batch._tau_column.cache_info().hits == 1
