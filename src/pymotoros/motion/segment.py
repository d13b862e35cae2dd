"""One segment of MotoROS's interpolation: the step grid and its pulse targets (§5.4).

A segment runs from the group's current point (start) to the pending point (end).
Its steps fall on a grid that continues across segments: the first step is the
leftover of the previous segment if there is one, then whole periods; the last step
lands exactly on the end time, and whatever part of its period it did not use becomes
the next leftover. Each step's position is the cubic of the specification; the
absolute target is truncated to pulses and the increment is the difference from the
previous target.

The whole segment is computed at once, vectorised; that gives the same numbers as the
step-by-step loop of the real code because no step depends on the one before except
through the integer grid and the previous pulse target.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.constants import SLOTS
from pymotoros.motion.numerics import coefficients, ms_to_seconds, positions, pulses, velocities
from pymotoros.motion.points import GroupPoint

F32Array = npt.NDArray[np.float32]
I64Array = npt.NDArray[np.int64]


@dataclass(frozen=True, slots=True)
class Grid:
    """The step times of one segment (all integer ms)."""

    first_ms: int
    """Time of the first step: start + leftover (or + period when there is none)."""
    full_steps: int
    """Steps strictly before the end time; then one final step at exactly the end."""
    leftover_ms: int
    """``timeLeftover_ms`` after the segment."""

    @property
    def entries(self) -> int:
        return self.full_steps + 1


def plan_grid(start_ms: int, end_ms: int, leftover_ms: int, period_ms: int) -> Grid:
    """The grid of a segment with end_ms > start_ms (§5.4 steps 4–5).

    Quirk kept: when the first step is the final one and lands exactly on the end, the
    leftover is left as it was (it is only recomputed when the final step overshoots).
    """
    first = start_ms + (leftover_ms or period_ms)
    if first >= end_ms:
        return Grid(first, 0, first - end_ms if first > end_ms else leftover_ms)
    full = (end_ms - first + period_ms - 1) // period_ms
    # A full step resets the leftover to 0, so an exact landing leaves 0.
    return Grid(first, full, first + full * period_ms - end_ms)


@dataclass(frozen=True, slots=True, eq=False)
class Segment:
    """The computed steps of one segment, ready to be queued."""

    start: GroupPoint
    end: GroupPoint
    grid: Grid
    times: list[int]
    """Entry times, ms; the last one is the end time."""
    targets: I64Array
    """Absolute pulse target of each entry, shape (entries, num_axes), column j holding
    controller slot ``axes.axis_slots[j]``."""
    increments: I64Array
    """Shape (entries, 8): pulse increments in controller order, 0 where no axis."""
    tau: F32Array
    """τ of each full step (s, float32)."""
    a1: F32Array
    a2: F32Array
    pos: F32Array
    """Interpolated float32 positions (entries, num_axes), ROS order; last row = end."""
    mode: FloatMode

    def state_at(self, index: int) -> GroupPoint:
        """The group's current point once entry ``index`` has been computed."""
        if index == len(self.times) - 1:
            return self.end
        n = self.a1.shape[-1]
        pos = self.start.pos.copy()
        pos[:n] = self.pos[index]
        vel = self.start.vel.copy()
        tau = self.tau[index : index + 1]
        vel[:n] = velocities(self.start.vel[:n], self.a1, self.a2, tau, self.mode)
        return GroupPoint(self.times[index], pos, vel)


def compute_segment(
    start: GroupPoint,
    end: GroupPoint,
    leftover_ms: int,
    previous: tuple[int, ...],
    axes: GroupAxes,
) -> Segment | None:
    """Every step of the segment start → end, or None if end is not after start.

    ``previous`` is prevPulsePos (8 slots, controller order).
    """
    if end.time_ms <= start.time_ms:
        return None
    mode = axes.float_mode
    n = axes.num_axes
    grid = plan_grid(start.time_ms, end.time_ms, leftover_ms, axes.period_ms)
    duration = ms_to_seconds(np.array([end.time_ms - start.time_ms]), mode)
    x0, v0 = start.pos[:n], start.vel[:n]
    a1, a2 = coefficients(x0, v0, end.pos[:n], end.vel[:n], duration, mode)
    steps = grid.first_ms + axes.period_ms * np.arange(grid.full_steps, dtype=np.int64)
    tau = ms_to_seconds(steps - start.time_ms, mode)
    pos = np.empty((grid.entries, n), dtype=np.float32)
    pos[:-1] = positions(x0, v0, a1, a2, tau[:, None], mode)
    pos[-1] = end.pos[:n]
    targets = pulses(pos, axes.factors_ros, mode)[:, axes.columns]
    increments = np.zeros((grid.entries, SLOTS), dtype=np.int64)
    slots = list(axes.axis_slots)
    increments[0, slots] = targets[0] - np.array([previous[s] for s in slots], dtype=np.int64)
    increments[1:, slots] = np.diff(targets, axis=0)
    times = steps.tolist()
    times.append(end.time_ms)
    return Segment(start, end, grid, times, targets, increments, tau, a1, a2, pos, mode)
