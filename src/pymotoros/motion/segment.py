"""The step grid of one segment of MotoROS's interpolation (§5.4).

A segment runs from the group's current point (start) to the pending point (end).
Its steps fall on a grid that continues across segments: the first step is the
leftover of the previous segment if there is one, then whole periods; the last step
lands exactly on the end time, and whatever part of its period it did not use becomes
the next leftover. The grid is integer arithmetic, shared by the tick-by-tick engine
(:mod:`pymotoros.motion.interpolator`) and, in the same arithmetic, the offline one
(:mod:`pymotoros.motion.offline`); the pulses of the steps are computed there.
"""

from __future__ import annotations

from typing import NamedTuple


class Grid(NamedTuple):
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
