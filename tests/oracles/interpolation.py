"""The interpolator's reference route: every planned segment at once, numpy kernels only.

The library computes a lone small segment in plain Python
(``GroupInterpolator._compute_small``) and the queue's oldest long segment alone
(``GroupInterpolator._compute_front``). Here every segment not computed yet goes
through :func:`pymotoros.motion.batch.queued_targets` in one call when anything needs
a pulse: the general vectorised kernel, as the tick engine computed before those
shortcuts. :func:`all_at_once` installs it for the controllers built inside it.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from pymotoros.motion import SLOTS, GroupInterpolator
from pymotoros.motion.batch import queued_targets


def compute_all(self: GroupInterpolator) -> None:
    """Every planned segment not computed yet, in order, by the numpy kernels."""
    segments = self._uncomputed
    if not segments:
        return
    self._uncomputed = []
    axes = self.axes
    n = axes.num_axes
    raw = b"".join([p for s in segments for p in (s.start.packed(), s.end.packed())])
    rows = np.frombuffer(raw, dtype=np.float32).reshape(len(segments), 4, SLOTS)[:, :, :n]
    period = axes.period_ms
    grids = [
        (s.start.time_ms, s.end.time_ms, s.grid.first_ms + period * s.step0, s.steps, s.last)
        for s in segments
    ]
    times, targets = queued_targets(rows.transpose(1, 0, 2), grids, axes)
    self._store(segments, times, targets, self._chain_prev)


@contextmanager
def all_at_once() -> Iterator[None]:
    """Interpolators made inside compute through :func:`compute_all` only."""
    saved = GroupInterpolator._compute, GroupInterpolator._compute_front
    GroupInterpolator._compute = compute_all  # type: ignore[method-assign]
    GroupInterpolator._compute_front = compute_all  # type: ignore[method-assign]
    try:
        yield
    finally:
        GroupInterpolator._compute, GroupInterpolator._compute_front = saved  # type: ignore[method-assign]
