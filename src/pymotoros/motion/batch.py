"""Many segments at once: the vectorised core shared by the offline engine and the
tick-by-tick engine (which computes the segments waiting in its queue in one go).

Given each segment's start and end points and its step grid (see
:func:`pymotoros.motion.segment.plan_grid`), it returns every step's time and absolute
pulse target. The arithmetic per element is the one of
:func:`pymotoros.motion.segment.compute_segment`: coefficients in longdouble (x87) or
float32 (FS100), positions with :func:`~pymotoros.motion.numerics.positions_x87_checked`
or :func:`~pymotoros.motion.numerics.positions_single`; the tests check both engines
against each other and against an exact rational model.
"""

from __future__ import annotations

from typing import Final

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.numerics import (
    coefficients_kernel,
    coefficients_x87_checked,
    ms_to_seconds,
    position_bound,
    positions_single,
    positions_x87_checked,
    pulses,
)

F32Array = npt.NDArray[np.float32]
I64Array = npt.NDArray[np.int64]

CHUNK: Final = 2048
"""Steps per block of the kernel: (2048 × 6) float64 = 96 KiB temporaries. Large
temporaries would cost more in fresh memory pages than in arithmetic."""


def batch_targets(
    rows: F32Array,
    start_ms: I64Array,
    end_ms: I64Array,
    first_ms: I64Array,
    full: I64Array,
    axes: GroupAxes,
) -> tuple[I64Array, I64Array]:
    """(time_ms (N,), targets (N, num_axes)) of S segments, in order.

    ``rows`` is (4, S, num_axes) float32: start positions, start velocities, end
    positions, end velocities (ROS order); ``start_ms``, ``end_ms``, ``first_ms`` and
    ``full`` (S,) describe each grid. Target column j is controller slot
    ``axes.axis_slots[j]``.
    """
    mode = axes.float_mode
    n = axes.num_axes
    period = axes.period_ms
    counts = full + 1
    total = int(counts.sum())
    seg = np.repeat(np.arange(len(counts)), counts)
    k = np.arange(total, dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
    final = k == full[seg]
    step_ms = first_ms[seg] + period * k
    time_ms: I64Array = np.where(final, end_ms[seg], step_ms).astype(np.int64, copy=False)
    duration = ms_to_seconds(end_ms - start_ms)[:, None]
    tau = ms_to_seconds(step_ms - start_ms[seg])[:, None]
    targets = np.empty((total, n), dtype=np.int64)
    x1 = rows[2]
    with np.errstate(all="ignore"):
        if mode is FloatMode.X87_EXTENDED:
            rows64 = rows.astype(np.float64)
            t64 = duration.astype(np.float64)
            coef = coefficients_x87_checked(rows64, t64)
            h1 = coef[0].astype(np.float64) * 0.5
            a2 = coef[1].astype(np.float64)
            x0, v0 = rows64[0], rows64[1]
            bound = position_bound(x0, v0, h1, a2, t64)
            tau64 = tau.astype(np.float64)
        else:
            tt32 = duration * duration
            coef = coefficients_kernel(
                rows, np.array((tt32, tt32 * duration)), np.array((duration, tt32)), mode
            )
        for lo in range(0, total, CHUNK):
            hi = min(lo + CHUNK, total)
            sg = seg[lo:hi]
            if mode is FloatMode.X87_EXTENDED:
                pos = positions_x87_checked(x0[sg], v0[sg], h1[sg], a2[sg], tau64[lo:hi], bound[sg])
            else:
                pos = positions_single(
                    rows[0][sg], rows[1][sg], coef[0][sg], coef[1][sg], tau[lo:hi]
                )
            fin = final[lo:hi]
            pos[fin] = x1[sg[fin]]
            part = pulses(pos, axes.factors_ros, mode)
            targets[lo:hi] = part if axes.identity_columns else part[:, axes.columns]
    return time_ms, targets
