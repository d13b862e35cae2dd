"""Many segments at once: the vectorised core shared by the offline engine and the
tick-by-tick engine (which computes the segments waiting in its queue in one go).

Given each segment's start and end points and its step grid (see
:func:`pymotoros.motion.segment.plan_grid`), it returns every step's time and absolute
pulse target. The arithmetic per element is the one of
:func:`pymotoros.motion.one_segment.compute_segment`: coefficients in longdouble (x87) or
float32 (FS100), positions with :func:`~pymotoros.motion.numerics.positions_x87_checked`
or :func:`~pymotoros.motion.numerics.positions_single`; the tests check both engines
against each other and against an exact rational model.

How it is organised, for speed:

* the last entry of a segment is its end point, whose target is the pulse value of the
  end position: no coefficient is computed for a segment made of that entry alone
  (frequent when points are as dense as the period);
* :func:`batch_increments` (whole trajectories) works in blocks of
  :data:`SEGMENT_CHUNK` segments: their coefficients, then their steps rank by rank
  (step k of every segment at once, with each segment's terms used in place and, when
  the points are evenly spaced, written to a strided view of the output: no gather, no
  scatter; issue 13 measured this at twice the speed of a gather per step), then the
  pulses of each rank, and the increments of :data:`CHUNK` entries at a time. Segments longer than
  :data:`SHORT_STEPS` steps are computed first, :data:`CHUNK` steps at a time, each
  step taking its segment's terms with one gather. Small blocks keep every temporary
  array in the allocator's reused memory; large temporaries cost more in fresh memory
  pages than in arithmetic, so only the results are allocated at full size;
* :func:`queued_targets` (the tick engine's queue, a few hundred entries) does the
  grid bookkeeping in Python and sends every entry through one position kernel: at
  that size the cost is the number of numpy calls;
* :func:`segment_targets` (the tick engine's oldest queued segment on its own, when
  IncMove reaches it in real time) makes that count as small as it goes: coefficients
  in plain Python (one segment's dozen values), the τ column memoised per grid, one
  position kernel, no gather. About a third of the numpy calls of
  :func:`queued_targets`, so that no single tick pays for a whole queue.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any, Final, NamedTuple

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.numerics import (
    LD,
    RISK_FACTOR,
    coefficients_kernel,
    coefficients_x87_checked,
    coefficients_x87_exact,
    coefficients_x87_interval,
    f32,
    ms_to_seconds,
    position_bound,
    positions_single,
    positions_x87,
    positions_x87_checked,
    pulses,
)

F32Array = npt.NDArray[np.float32]
F64Array = npt.NDArray[np.float64]
I64Array = npt.NDArray[np.int64]
AnyArray = npt.NDArray[Any]

BlockDone = Callable[[I64Array, I64Array, int], None]
"""``on_block(time_ms, increments, done)``: entries ``[0, done)`` are final."""

CHUNK: Final = 2048
"""Steps (entries) per block of the position (pulse) kernel: (2048 × 6) float64 = 96
KiB temporaries."""

SEGMENT_CHUNK: Final = 1024
"""Segments per block of the coefficient kernel and of the short-segment kernel."""

SHORT_STEPS: Final = 32
"""Segments with at most this many steps are computed step rank by step rank
(:func:`_ranked_steps`: one pass per rank over the block), longer ones step by step
with a gather of their terms (:func:`_gathered_steps`), whose cost does not grow with
a segment's length."""


def batch_increments(
    rows: F32Array,
    start_ms: I64Array,
    end_ms: I64Array,
    first_ms: I64Array,
    full: I64Array,
    previous: I64Array,
    axes: GroupAxes,
    *,
    workers: int = 1,
    on_block: BlockDone | None = None,
) -> tuple[I64Array, I64Array]:
    """(time_ms (N,), increments (N, num_axes)) of S consecutive segments, in order.

    ``rows`` is (4, S, num_axes) float32: start positions, start velocities, end
    positions, end velocities (ROS order); ``start_ms``, ``end_ms``, ``first_ms`` and
    ``full`` (S,) describe each grid; ``previous`` (num_axes,) is the target before the
    first entry. Column j is controller slot ``axes.axis_slots[j]``. ``workers`` > 1
    computes the blocks of segments on that many threads (numpy releases the GIL in its
    loops); every element is computed by the same operations whatever the split, so the
    result does not depend on it. ``on_block(time_ms, increments, done)`` is called, in
    the caller's thread, each time entries ``[0, done)`` of the arrays being filled are
    final, so that a caller can write them while the rest is computed.
    """
    n = axes.num_axes
    size = len(full)
    stop = np.cumsum(full + 1)
    total = int(stop[-1]) if len(stop) else 0
    last = stop - 1
    time_ms: I64Array = np.empty(total, dtype=np.int64)
    time_ms[last] = end_ms
    # Each entry's absolute target first, turned into increments block by block; the
    # last entry of a segment is its end point.
    increments: I64Array = np.empty((total, n), dtype=np.int64)
    with np.errstate(all="ignore"):
        ends = pulses(rows[2], axes.factors_ros, axes.float_mode)
        if not axes.identity_columns:
            ends = ends[:, axes.columns]
    increments[last] = ends
    begin = last - full  # entry index of each segment's first entry
    long = full > SHORT_STEPS
    with np.errstate(all="ignore"):
        if long.any():
            where = np.flatnonzero(long)
            segments = _Segments(rows, start_ms, first_ms, end_ms, full, begin)
            _gathered_steps(segments.pick(where), axes, time_ms, increments)
    short = _Segments(rows, start_ms, first_ms, end_ms, np.where(long, 0, full), begin)

    def block(lo: int) -> None:
        hi = min(lo + SEGMENT_CHUNK, size)
        with np.errstate(all="ignore"):
            _ranked_steps(short.pick(slice(lo, hi)), axes, time_ms, increments)
            # The target before the block: the end point of the segment before it.
            _difference(
                increments, int(begin[lo]), int(stop[hi - 1]), previous if lo == 0 else ends[lo - 1]
            )

    starts = range(0, size, SEGMENT_CHUNK)
    if workers > 1 and len(starts) > 1:
        from concurrent.futures import ThreadPoolExecutor  # only for large batches

        with ThreadPoolExecutor(workers) as pool:
            for lo, _ in zip(starts, pool.map(block, starts), strict=True):
                if on_block is not None:
                    on_block(time_ms, increments, int(stop[min(lo + SEGMENT_CHUNK, size) - 1]))
    else:
        for lo in starts:
            block(lo)
            if on_block is not None:
                on_block(time_ms, increments, int(stop[min(lo + SEGMENT_CHUNK, size) - 1]))
    return time_ms, increments


def _difference(targets: I64Array, lo: int, hi: int, before: I64Array) -> None:
    """Targets [lo, hi) to increments in place, :data:`CHUNK` entries at a time from the
    end (so that each chunk still sees the target before it): no full-size temporary."""
    for a in range(lo + (hi - lo - 1) // CHUNK * CHUNK, lo - 1, -CHUNK):
        b = min(a + CHUNK, hi)
        np.subtract(targets[a + 1 : b], targets[a : b - 1], out=targets[a + 1 : b])
        targets[a] -= targets[a - 1] if a > lo else before


class _Segments(NamedTuple):
    """Some of :func:`batch_increments`'s segments: their rows (4, S, num_axes) and
    grids (S,), and ``begin``, the entry index of each one's first entry."""

    rows: F32Array
    start_ms: I64Array
    first_ms: I64Array
    end_ms: I64Array
    full: I64Array
    begin: I64Array

    def pick(self, where: Any) -> _Segments:
        """The segments ``where`` selects (a slice or an index array)."""
        rows, start_ms, first_ms, end_ms, full, begin = self
        return _Segments(
            rows[:, where],
            start_ms[where],
            first_ms[where],
            end_ms[where],
            full[where],
            begin[where],
        )


def _ranked_steps(
    segments: _Segments, axes: GroupAxes, time_ms: I64Array, targets: I64Array
) -> None:
    """The steps' targets of a block of short segments, rank by rank: step k of every segment that
    has one at once. Each segment's terms are used in place (no gather per step), and
    when every segment of the block has the same number of steps (points evenly
    spaced) the results go to a strided view of the output (no scatter)."""
    period = axes.period_ms
    steps = int(segments.full.max(initial=0))
    if not steps:
        return
    busy = segments.full > 0
    if not busy.all():
        segments = segments.pick(np.flatnonzero(busy))
    rows, start_ms, first_ms, end_ms, full, begin = segments
    count = len(full)
    duration = ms_to_seconds(end_ms - start_ms)[:, None]
    x87 = axes.float_mode is FloatMode.X87_EXTENDED
    if x87:
        x0, v0, h1, a2, bound = _terms_x87_split(rows, duration)
    else:
        x0, v0, h1, a2 = _terms_single(rows, duration).transpose(1, 0, 2)
    lead = first_ms - start_ms
    uniform = bool(full.min() == steps) and int(begin[-1] - begin[0]) == (steps + 1) * (count - 1)
    if uniform:
        lo = int(begin[0])
        hi = lo + (steps + 1) * count
        target_view = targets[lo:hi].reshape(count, steps + 1, -1)
        time_view = time_ms[lo:hi].reshape(count, steps + 1)
    for k in range(steps):
        if uniform or bool(full.min() > k):
            pick: Any = slice(None)
        else:
            pick = np.flatnonzero(full > k)
        tau = ms_to_seconds(lead[pick] + period * k)[:, None]
        if x87:
            pos = positions_x87_checked(
                x0[pick], v0[pick], h1[pick], a2[pick], tau.astype(np.float64), bound[pick]
            )
        else:
            pos = positions_single(x0[pick], v0[pick], h1[pick], a2[pick], tau)
        part = pulses(pos, axes.factors_ros, axes.float_mode)
        if not axes.identity_columns:
            part = part[:, axes.columns]
        if uniform:
            target_view[:, k] = part
            time_view[:, k] = first_ms + period * k
        else:
            index = begin[pick] + k
            targets[index] = part
            time_ms[index] = first_ms[pick] + period * k


def _gathered_steps(
    segments: _Segments, axes: GroupAxes, time_ms: I64Array, targets: I64Array
) -> None:
    """The steps' targets of long segments (all with at least one step), :data:`CHUNK` steps at a
    time, each step taking its segment's terms with one gather."""
    mode = axes.float_mode
    period = axes.period_ms
    rows, start_ms, first_ms, end_ms, steps, begin = segments
    # Step k of a segment whose steps start at global step g is g + k = ramp.
    count = int(steps.sum())
    local = np.repeat(np.arange(len(steps)), steps)
    offset = np.cumsum(steps) - steps
    ramp = np.arange(count, dtype=np.int64)
    step_ms = np.repeat(first_ms - period * offset, steps) + period * ramp
    index = np.repeat(begin - offset, steps) + ramp  # entry index of each step
    time_ms[index] = step_ms
    tau = ms_to_seconds(np.repeat(first_ms - start_ms - period * offset, steps) + period * ramp)
    duration = ms_to_seconds(end_ms - start_ms)[:, None]
    x87 = mode is FloatMode.X87_EXTENDED
    terms: AnyArray = _terms_x87(rows, duration) if x87 else _terms_single(rows, duration)
    tau_k: AnyArray = (tau.astype(np.float64) if x87 else tau)[:, None]
    for lo in range(0, count, CHUNK):
        hi = min(lo + CHUNK, count)
        per = terms[local[lo:hi]]
        if x87:
            pos = positions_x87_checked(
                per[:, 0], per[:, 1], per[:, 2], per[:, 3], tau_k[lo:hi], per[:, 4]
            )
        else:
            pos = positions_single(per[:, 0], per[:, 1], per[:, 2], per[:, 3], tau_k[lo:hi])
        part = pulses(pos, axes.factors_ros, mode)
        targets[index[lo:hi]] = part if axes.identity_columns else part[:, axes.columns]


def queued_targets(
    rows: F32Array, grids: Sequence[tuple[int, int, int, int, bool]], axes: GroupAxes
) -> tuple[list[int], I64Array]:
    """:func:`batch_increments` for the tick engine: (entry times, absolute targets) of
    the segments waiting in a queue, a few hundred entries at most.

    ``grids`` holds (start ms, end ms, first step ms, steps, ends) per segment (or
    piece of a segment: its steps from the first one given, then the end point if
    ``with_end``). At this size the cost is the number of numpy calls, not the arithmetic,
    so the grid bookkeeping is done in Python and every entry goes through one
    position kernel: the last entry of a segment takes the terms (x1, 0, 0, 0) at τ = 0,
    which give x1 exactly and are never close to a rounding boundary.
    """
    mode = axes.float_mode
    period = axes.period_ms
    count = len(grids)
    times: list[int] = []
    pick: list[int] = []
    tau_ms: list[int] = []
    lengths: list[int] = []
    for j, (start, end, first, full, with_end) in enumerate(grids):
        lengths.append(end - start)
        if full:
            stop = first + period * full
            times += range(first, stop, period)
            tau_ms += range(first - start, stop - start, period)
            pick += [j] * full
        if with_end:
            times.append(end)
            tau_ms.append(0)
            pick.append(count + j)
    duration = ms_to_seconds(np.array(lengths))[:, None]
    tau = ms_to_seconds(np.array(tau_ms))[:, None]
    with np.errstate(all="ignore"):
        if mode is FloatMode.X87_EXTENDED:
            terms = _terms_x87(rows, duration)
            ends = np.zeros_like(terms)
            ends[:, 0] = rows[2]
            ends[:, 4] = -1.0
            per = np.concatenate((terms, ends))[pick]
            pos = positions_x87_checked(
                per[:, 0], per[:, 1], per[:, 2], per[:, 3], tau.astype(np.float64), per[:, 4]
            )
        else:
            terms32 = _terms_single(rows, duration)
            ends32 = np.zeros_like(terms32)
            ends32[:, 0] = rows[2]
            per32 = np.concatenate((terms32, ends32))[pick]
            pos = positions_single(per32[:, 0], per32[:, 1], per32[:, 2], per32[:, 3], tau)
        part = pulses(pos, axes.factors_ros, mode)
    return times, part if axes.identity_columns else part[:, axes.columns]


TAU_CACHE: Final = 256
"""Most (first step, steps, period) keys :func:`_tau_column` remembers. Only a piece's
own grid is remembered (its first step within one period of its start: every whole
segment, and the first piece of a long one), so the keys are at most period × 200 and
points at a fixed spacing repeat a handful; the cap bounds the memo to about 2 MiB
(200 steps × 44 bytes per key) whatever the client sends. The later pieces of a long
segment, each with its own offset, are computed afresh."""


@functools.lru_cache(maxsize=TAU_CACHE)
def _tau_column(lead_ms: int, steps: int, period_ms: int) -> tuple[F64Array, F32Array, F64Array]:
    """τ of ``steps`` steps whose first is ``lead_ms`` after the segment's start, as
    :func:`queued_targets` makes them (float32 values; (steps, 1) as float64 for the
    x87 kernel and as float32 for the FS100 one), and (steps, 4) float64 powers
    1, τ, τ², τ³/6 for :func:`positions_x87_interval`. A memo of a pure function of
    these integers, read-only so that no caller can change what the next one gets."""
    tau = ms_to_seconds(np.arange(lead_ms, lead_ms + period_ms * steps, period_ms))[:, None]
    wide = tau.astype(np.float64)
    tau2 = wide * wide  # exact: 48 bits
    powers = np.hstack((np.ones_like(wide), wide, tau2, tau2 * wide / 6))
    for array in (tau, wide, powers):
        array.flags.writeable = False
    return wide, tau, powers


POSITION_WIDTH: Final = (RISK_FACTOR + 4.0) * 2.0**-53
"""Half-width of :func:`positions_x87_interval`'s interval, relative to the magnitude sum
M of a segment's terms (x0, v0·T, a1/2·T², a2·T³/6). Its float64 value F differs from the
exact position by at most 6.01 × 2⁻⁵³ × M (each term at most three roundings, the three
sums one each, whatever the order or fused multiply-adds) and the x87's by far less
(2⁻⁶⁴ per operation), so RISK_FACTOR (33) × 2⁻⁵³ × M covers |F − x87| more than five
times over; 4 × 2⁻⁵³ × M more covers the rounding of F ± the half-width (|F| ≤ 1.01 M)."""


def positions_x87_interval(
    terms: F64Array, wide: F64Array, powers: F64Array, sizes: Sequence[float]
) -> F32Array:
    """The x87's float32 positions of one segment, checked as an interval.

    ``terms`` (4, n) float64: x0, v0, a1/2 and a2 (float32 values); ``wide`` (K, 1) and
    ``powers`` (K, 4) from :func:`_tau_column`; ``sizes`` (n,) the magnitude sums M
    of each axis's terms over the whole segment (so over every τ ≤ T). F = x0 + v0·τ +
    a1/2·τ² + a2·(τ³/6) as one matrix product (powers · terms: the summation order and
    any fused multiply-add are the library's, which the bound allows) instead of the ten
    numpy calls of :func:`~pymotoros.motion.numerics.positions_x87_checked`'s
    expression; the x87's value
    X lies within :data:`POSITION_WIDTH` × M of F, and rounding to float32 is monotonic,
    so where F − w and F + w round to the same float32, X does too (the argument of
    :func:`~pymotoros.motion.numerics.small_segment_x87`, vectorised). The other elements
    are recomputed in longdouble, as the x87 does
    (:func:`~pymotoros.motion.numerics.positions_x87`). Values must be tame (no overflow).
    """
    value = np.dot(powers, terms)
    width = [m * POSITION_WIDTH for m in sizes]
    ends: F32Array = (value + np.array([[[-w for w in width]], [width]])).astype(np.float32)
    low: F32Array = ends[0]
    unsure = low != ends[1]
    if unsure.any():
        rows, cols = np.nonzero(unsure)
        lt = wide[rows, 0].astype(LD)
        low[rows, cols] = positions_x87(
            terms[0, cols].astype(LD),
            terms[1, cols].astype(LD),
            terms[2, cols].astype(LD),
            terms[3, cols].astype(LD),
            lt,
            lt * lt,
        )
    return low


def segment_targets(
    start: tuple[Sequence[float], Sequence[float]],
    end: tuple[Sequence[float], Sequence[float]],
    length_ms: int,
    lead_ms: int,
    steps: int,
    with_end: bool,
    axes: GroupAxes,
) -> I64Array:
    """Absolute targets (``steps`` + ``with_end`` rows, columns as
    :func:`queued_targets`) of one segment (or piece): what :func:`queued_targets`
    returns for it alone, with about a third of the numpy calls.

    ``start`` and ``end`` are (positions, velocities), ``num_axes`` float32 values each
    in ROS order, all finite and tame (:attr:`~pymotoros.motion.points.GroupPoint.tame`:
    no operation overflows, so numpy's error state is left alone); ``length_ms`` is the
    segment's length, ``lead_ms`` its first step's offset from its start. Every value
    is the one :func:`queued_targets` computes, by the same reasoning: on the x87 the
    coefficients come from :func:`coefficients_x87_interval` (checked in float64) or
    :func:`coefficients_x87_exact` (longdouble), both the x87's float32 values as
    :func:`coefficients_x87_checked` gives them (a zero's sign aside, which no pulse
    sees), and the positions from :func:`positions_x87_interval`, the x87's float32
    values as :func:`positions_x87_checked` gives them (both checked against the
    same error bound, or recomputed in longdouble); on the FS100 the coefficient and
    position kernels are the general path's, each element computed by the same float32
    operations. The end entry is the end position in pulses, as there.
    """
    mode = axes.float_mode
    x0, v0 = start
    x1, v1 = end
    n = len(x0)
    pos: F32Array = np.empty((steps + with_end, n), dtype=np.float32)
    if with_end:
        pos[steps] = x1
    if steps:
        period = axes.period_ms
        column = _tau_column if lead_ms <= period else _tau_column.__wrapped__
        wide, tau, powers = column(lead_ms, steps, period)
        duration = f32(length_ms / 1000)  # ms_to_seconds, as a Python float
        if mode is FloatMode.X87_EXTENDED:
            coef: Sequence[float] | None = coefficients_x87_interval(x0, v0, x1, v1, duration)
            if coef is None:
                coef = coefficients_x87_exact(x0, v0, x1, v1, duration)
            h1 = [c / 2 for c in coef[:n]]  # a1/2: exact
            a2 = coef[n:]
            t, tt = duration, duration * duration
            ttt6 = tt * t / 6
            sizes = [
                abs(p) + abs(s) * t + abs(h) * tt + abs(c) * ttt6
                for p, s, h, c in zip(x0, v0, h1, a2, strict=True)
            ]
            terms = np.array([x0, v0, h1, a2])
            pos[:steps] = positions_x87_interval(terms, wide, powers, sizes)
        else:
            rows = np.array([x0, v0, x1, v1], dtype=np.float32)[:, None]
            x0s, v0s, a1s, a2s = _terms_single(rows, np.array([[duration]], dtype=np.float32))[0]
            pos[:steps] = positions_single(x0s, v0s, a1s, a2s, tau)
    part = pulses(pos, axes.factors_ros, mode)
    return part if axes.identity_columns else part[:, axes.columns]


def _by_blocks(
    terms: Callable[[F32Array, F32Array], AnyArray],
    rows: F32Array,
    duration: F32Array,
    width: int,
    dtype: type[np.floating[Any]],
) -> AnyArray:
    """``terms`` of many segments, :data:`SEGMENT_CHUNK` segments at a time, into one
    (S, width, n) array: the kernels' temporaries stay the size of a block."""
    size = rows.shape[1]
    out: AnyArray = np.empty((size, width, rows.shape[2]), dtype=dtype)
    for lo in range(0, size, SEGMENT_CHUNK):
        hi = lo + SEGMENT_CHUNK
        out[lo:hi] = terms(rows[:, lo:hi], duration[lo:hi])
    return out


def _terms_x87(rows: F32Array, duration: F32Array) -> F64Array:
    """(S, 5, n) float64: x0, v0, a1/2, a2 and the risk bound of each segment (x87)."""
    if rows.shape[1] > SEGMENT_CHUNK:
        return _by_blocks(_terms_x87, rows, duration, 5, np.float64)
    return np.stack(_terms_x87_split(rows, duration), axis=1)


def _terms_x87_split(
    rows: F32Array, duration: F32Array
) -> tuple[F64Array, F64Array, F64Array, F64Array, F64Array]:
    """x0, v0, a1/2, a2 and the risk bound of each segment (x87), each (S, n) float64."""
    rows64 = rows.astype(np.float64)
    t64 = duration.astype(np.float64)
    coef = coefficients_x87_checked(rows64, t64).astype(np.float64)
    coef[0] *= 0.5  # a1/2: exact
    x0, v0 = rows64[0], rows64[1]
    return x0, v0, coef[0], coef[1], position_bound(x0, v0, coef[0], coef[1], t64)


def _terms_single(rows: F32Array, duration: F32Array) -> F32Array:
    """(S, 4, n) float32: x0, v0, a1 and a2 of each segment (FS100)."""
    if rows.shape[1] > SEGMENT_CHUNK:
        return _by_blocks(_terms_single, rows, duration, 4, np.float32)
    tt32 = duration * duration
    coef = coefficients_kernel(
        rows, np.array((tt32, tt32 * duration)), np.array((duration, tt32)), FloatMode.STRICT_SINGLE
    )
    return np.stack((rows[0], rows[1], coef[0], coef[1]), axis=1)
