"""Every group's increment queue and pending point, as MotoROS clears them."""

from __future__ import annotations

from collections.abc import Sequence

from pymotoros.motion import GroupInterpolator


class MotionQueues:
    """The AddToIncQueue queues of all groups (one :class:`GroupInterpolator` each)."""

    def __init__(self, interpolators: Sequence[GroupInterpolator]) -> None:
        self.interpolators = tuple(interpolators)

    def has_queued_motion(self) -> bool:
        return any(len(i.queue) for i in self.interpolators)

    def any_pending(self) -> bool:
        """A point is still waiting to be interpolated in some group."""
        return any(i.pending for i in self.interpolators)

    def clear(self) -> None:
        """Ros_MotionServer_ClearQ_All: every queue and pending point."""
        for interp in self.interpolators:
            interp.clear()
