"""When the robot is at rest: ``in_motion`` false and the feedback still for a few
state cycles in a row (:class:`RestDetector`), what a move's start ("start from current")
and its end (settled at the goal, or stopped) wait for.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from pymotoros.client.following import (
    joined_positions,
)
from pymotoros.client.state import RobotState

SETTLE_STEP: Final = 2e-5
"""rad (m): feedback that moves less than this between two state messages is at rest."""


SETTLE_SAMPLES: Final = 3
"""Consecutive quiet state messages needed to call the robot settled (~75 ms at 40 Hz)."""


class RestDetector:
    """Counts state cycles (one per ROBOT_STATUS) with ``in_motion`` false and still feedback."""

    def __init__(self, groups: Sequence[int]) -> None:
        self.groups = tuple(groups)
        self.quiet = 0
        self._cycle = -1
        self._prev: tuple[float, ...] | None = None

    def update(self, state: RobotState) -> bool:
        """True once the robot has been at rest for :data:`SETTLE_SAMPLES` cycles."""
        if state.status_count != self._cycle and state.status is not None:
            self._cycle = state.status_count
            pos = joined_positions(state, self.groups)
            still = (
                pos is not None
                and self._prev is not None
                and all(abs(a - b) <= SETTLE_STEP for a, b in zip(pos, self._prev, strict=True))
            )
            self.quiet = self.quiet + 1 if still and state.status.in_motion is False else 0
            self._prev = pos
        return self.quiet >= SETTLE_SAMPLES
