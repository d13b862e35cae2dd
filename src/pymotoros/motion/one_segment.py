"""One segment on its own, every step computed in one go: where a blocked segment stands.

:meth:`GroupInterpolator._abort <pymotoros.motion.interpolator.GroupInterpolator>`
needs the state at the step the AddToIncQueue task was blocked on (only that step is
computed, whatever the segment's length), and the tests use the whole form as their
literal per-segment model (same arithmetic, element by element). The queue's segments
are computed by :mod:`pymotoros.motion.batch`.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable
from dataclasses import dataclass
from itertools import repeat
from operator import add

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.constants import SLOTS
from pymotoros.motion.numerics import (
    LD,
    coefficients_kernel,
    coefficients_x87_scalar,
    f32,
    f32_tuple,
    positions_single,
    positions_x87,
    pulse,
    pulses,
    velocities,
)
from pymotoros.motion.points import GroupPoint
from pymotoros.motion.queue import Increment
from pymotoros.motion.segment import Grid, plan_grid

F32Array = npt.NDArray[np.float32]
I64Array = npt.NDArray[np.int64]


@dataclass(frozen=True, slots=True, eq=False)
class OneSegment:
    """The computed steps of one segment, ready to be queued."""

    start: GroupPoint
    end: GroupPoint
    grid: Grid
    entries: list[Increment]
    """One queue entry per step; the last one is at the end time."""
    targets: I64Array
    """Absolute pulse target of each entry (entries, num_axes), column j = controller slot
    ``axes.axis_slots[j]``."""
    coef: F32Array
    """a1 and a2 stacked (2, num_axes), float32."""
    taus: list[float]
    """τ of each full step (s, float32 values)."""
    pos: F32Array | None
    """Interpolated float32 positions of the full steps (full_steps, num_axes), ROS order."""
    mode: FloatMode

    def state_at(self, index: int) -> GroupPoint:
        """The group's current point once entry ``index`` has been computed."""
        if index == len(self.entries) - 1 or self.pos is None:
            return self.end
        n = self.coef.shape[-1]
        tau = np.array([[self.taus[index]]], dtype=np.float32)
        v0 = np.array(self.start.vel[:n], dtype=np.float32)
        vel = velocities(v0, self.coef[0], self.coef[1], tau, self.mode)[0]
        return GroupPoint(
            self.entries[index].time_ms,
            tuple(self.pos[index].tolist()) + self.start.pos[n:],
            tuple(vel.tolist()) + self.start.vel[n:],
        )


def compute_segment(
    start: GroupPoint,
    end: GroupPoint,
    leftover_ms: int,
    previous: tuple[int, ...],
    tool: int,
    axes: GroupAxes,
    only: int | None = None,
) -> OneSegment | None:
    """Every step of the segment start → end, or None if end is not after start.

    With ``only``, just full step ``only`` (then the end point): what
    :meth:`GroupInterpolator._abort` needs, whatever the segment's length.

    ``previous`` is prevPulsePos (8 slots, controller order); ``tool`` is latched into
    every entry. Written for few numpy calls. The queue's segments are computed
    together (:func:`~pymotoros.motion.batch.queued_targets`); this one-segment form is
    what :meth:`GroupInterpolator._abort` needs to find where a blocked segment stands,
    and the tests' literal per-segment model (same arithmetic, element by element).
    """
    s_ms = start.time_ms
    if end.time_ms <= s_ms:
        return None
    mode = axes.float_mode
    n = axes.num_axes
    period = axes.period_ms
    grid = plan_grid(s_ms, end.time_ms, leftover_ms, period)
    if only is None:
        full = grid.full_steps
        steps = [grid.first_ms + period * k for k in range(full)]
    else:
        full = 1
        steps = [grid.first_ms + period * only]
    # (int ms)/1000 stored as float32. The exact quotient is never within 2⁻³⁵ of a
    # float32 rounding boundary, so float64 division then rounding gives the x87 value.
    duration = f32((end.time_ms - s_ms) / 1000)
    taus = list(f32_tuple([(c - s_ms) / 1000 for c in steps], full))
    x0, v0 = start.pos[:n], start.vel[:n]
    x1, v1 = end.pos[:n], end.vel[:n]
    pos: F32Array | None = None
    errors = contextlib.nullcontext() if start.tame and end.tame else np.errstate(all="ignore")
    with errors:
        if mode is FloatMode.X87_EXTENDED:
            fast = coefficients_x87_scalar(x0, v0, x1, v1, duration)
            if fast is None:
                rows = np.array([*x0, *v0, *x1, *v1], dtype=LD).reshape(4, n)
                et = LD(duration)
                tt = et * et
                den_a = np.array([[tt], [tt * et]], dtype=LD)
                den_b = np.array([[et], [tt]], dtype=LD)
                coef = coefficients_kernel(rows, den_a, den_b, mode)
            else:
                coef = np.array(fast, dtype=np.float32).reshape(2, n)
            if full:
                # x0, v0, a1/2 and a2 as one longdouble array (a1/2 is exact); for a
                # few steps the longdouble kernel is cheaper than the checked float64
                # one the offline engine uses (same results).
                co = coef.tolist() if fast is None else [fast[:n], fast[n:]]
                flat = [*x0, *v0, *(c / 2 for c in co[0]), *co[1]]
                terms = np.array(flat, dtype=np.float64).reshape(4, n).astype(LD)
                lt = np.array(taus, dtype=np.float64).reshape(full, 1).astype(LD)
                pos = positions_x87(terms[0], terms[1], terms[2], terms[3], lt, lt * lt)
        else:
            rows32 = np.array([*x0, *v0, *x1, *v1], dtype=np.float32).reshape(4, n)
            t32 = np.float32(duration)
            tt32 = t32 * t32
            den_a = np.array([[tt32], [tt32 * t32]], dtype=np.float32)
            den_b = np.array([[t32], [tt32]], dtype=np.float32)
            coef = coefficients_kernel(rows32, den_a, den_b, mode)
            if full:
                tau = np.array(taus, dtype=np.float32).reshape(full, 1)
                pos = positions_single(rows32[0], rows32[1], coef[0], coef[1], tau)
    # Absolute targets (row 0: prevPulsePos), truncated from the exact products.
    targets = np.empty((full + 2, n), dtype=np.int64)
    targets[0] = axes.take(previous)
    factors = axes.factors_ros_list
    last = [pulse(x, f, mode) for x, f in zip(x1, factors, strict=True)]
    if pos is not None:
        ros = pulses(pos, axes.factors_ros, mode)
        targets[1 : full + 1] = ros if axes.identity_columns else ros[:, axes.columns]
    targets[full + 1] = last if axes.identity_columns else [last[j] for j in axes.columns_list]
    entries = make_entries([*steps, end.time_ms], targets, tool, axes)
    return OneSegment(start, end, grid, entries, targets[1:], coef, taus, pos, mode)


def make_entries(
    times: list[int], chain: I64Array, tool: int | list[int], axes: GroupAxes
) -> list[Increment]:
    """Queue entries from absolute targets: ``chain`` row 0 is the previous target, row
    k + 1 the target of entry k (valid slots in ascending order); ``tool`` for every
    entry or one per entry."""
    incs = (chain[1:] - chain[:-1]).tolist()
    if axes.contiguous:
        pad = (0,) * (SLOTS - axes.num_axes)
        spread: Iterable[tuple[int, ...]] = map(add, map(tuple, incs), repeat(pad))
    else:
        spread = (spread_row(row, axes.axis_slots) for row in incs)
    # tuple.__new__ builds each NamedTuple without a Python-level call
    tools = repeat(tool) if isinstance(tool, int) else tool
    return list(map(tuple.__new__, repeat(Increment), zip(times, spread, tools, strict=False)))


def spread_row(row: list[int], slots: tuple[int, ...]) -> tuple[int, ...]:
    out = [0] * SLOTS
    for value, slot in zip(row, slots, strict=True):
        out[slot] = value
    return tuple(out)
