"""What a move reports when it reaches its goal: :class:`MoveResult` (the plan, where the
robot ended, how long it took) with how the points went out (:class:`StreamStats`) and
how the robot followed (:class:`~pymotoros.client.following.FollowingReport`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from pymotoros.client.following import FollowingReport
from pymotoros.client.planning import JointTrajectory


@dataclass(slots=True)
class StreamStats:
    """What streaming one trajectory took."""

    points: int = 0
    busy_replies: int = 0
    max_busy_wait_s: float = 0.0
    elapsed_s: float = 0.0

    @property
    def offers(self) -> int:
        """Points sent, retries included: each offer was accepted or answered BUSY."""
        return self.points + self.busy_replies


@dataclass(frozen=True, slots=True)
class MoveResult:
    """How a move went."""

    trajectory: JointTrajectory
    final_positions: tuple[float, ...]
    stream: StreamStats
    following: FollowingReport
    elapsed_s: float
    """From the first point sent to settled at the goal."""
    groups: tuple[int, ...] = field(default=(0,))
