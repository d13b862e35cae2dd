"""Every group's increment queue and pending point, as MotoROS clears them."""

from __future__ import annotations

from collections.abc import Sequence

from pymotoros.motion import GroupInterpolator


class MotionQueues:
    """The AddToIncQueue queues of all groups (one :class:`GroupInterpolator` each)."""

    def __init__(self, interpolators: Sequence[GroupInterpolator]) -> None:
        self.interpolators = tuple(interpolators)
        self.cleared_at_close = 0
        """Fidelity safe: the increments (the longest group's queue, one per period) that
        the motion connection's close cleared and MotoROS 1.9.12 would have kept for the
        next connection to resume (§2.2); 0 when none. Any later clear forgets it, as it
        would empty the robot's kept queues (an alarm, a mode change …)."""

    def has_queued_motion(self) -> bool:
        return any(len(i.queue) for i in self.interpolators)

    def longest(self) -> int:
        """Increments in the fullest group's queue: the periods the queued motion lasts."""
        return max((len(i.queue) for i in self.interpolators), default=0)

    def any_pending(self) -> bool:
        """A point is still waiting to be interpolated in some group."""
        return any(i.pending for i in self.interpolators)

    def clear(self) -> None:
        """Ros_MotionServer_ClearQ_All: every queue and pending point."""
        for interp in self.interpolators:
            interp.clear()
        self.cleared_at_close = 0
