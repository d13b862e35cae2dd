"""How fast a trajectory's points are offered to MotoROS: the BUSY back-off, the
:class:`BusyPolicy` of the first offer, and :class:`Pacing`, the estimate of how much
accepted motion is still queued ahead of the robot (which decides how long a retry may wait).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Final

DEFAULT_BUSY_TIMEOUT_S: Final = 10.0
"""How long one point may keep getting BUSY. A full queue is 0.8 s of motion (§5.1);
a safety speed limit can stretch that, so the budget is generous."""


BUSY_BACKOFF_FIRST_S: Final = 0.0005


BUSY_BACKOFF_MAX_S: Final = 0.002
"""Retry BUSY after 0.5 ms, doubling up to 2 ms. MotoROS frees its one pending-point slot
at an interpolation tick (4 ms, §5.3), so with points one tick apart a longer back-off
(the ROS driver waits ~5 ms) cannot keep the 200-entry queue fed and the robot lags.
Any gap under one tick lands a retry in the tick interval right after the slot frees:
the point is taken at the earliest tick it can be."""


BUSY_KEEP_AHEAD_S: Final = 0.2
"""Motion the client keeps queued ahead of the robot before it waits longer than the
back-off above: with more than this buffered, a BUSY retry waits up to one segment's
duration instead (the pending slot frees once the segment before it is queued, §5.3),
so a full queue costs about one BUSY per point instead of one every millisecond.
0.2 s is a quarter of MotoROS's 200-entry queue at 4 ms (0.8 s, §5.1): far more than
a LAN round trip or a scheduling hiccup of the client."""


BUSY_RELAXED_MAX_S: Final = 0.1
"""Longest single wait before an offer or between BUSY retries, so a lost connection is
still noticed fast: a tenth of the state-stall bound (``DEFAULT_STATE_STALL_S``, 1 s)."""


class BusyPolicy(enum.StrEnum):
    """When the next point is first offered (:attr:`TrajectoryStreamer.busy_policy`).

    Both retry BUSY the same way (:data:`BUSY_BACKOFF_FIRST_S`, :data:`BUSY_KEEP_AHEAD_S`)
    and give the robot the same motion; they differ in the first offer of each point.
    """

    PACED = "paced"
    """The default. A point that follows an accepted point (sequence > 0) is not offered
    before one interpolation period after that point was *sent*, nor, while more than
    :data:`BUSY_KEEP_AHEAD_S` is queued, before the relaxed wait
    (:meth:`Pacing.first_wait`). MotoROS clears its pending-point
    flag only in its AddToIncQueue task, once per tick (§5.3): an offer in the same tick
    interval as the previous acceptance is certain to get BUSY. About one offer per
    point instead of two (points far apart) to four or five (points one tick apart)."""
    IMMEDIATE = "immediate"
    """Offer every point the moment the previous one was accepted, as pymotoros did up
    to issue 22 (kept so that tests can show both give the robot the same increments)."""


@dataclass(slots=True)
class Pacing:
    """How much accepted motion is still ahead of the robot, estimated from the clock,
    and when MotoROS can next take a point.

    The robot cannot be ahead of the trajectory's own time since point 0 was accepted
    (it can only be behind, under HOLD or a safety speed limit), so ``last point's time
    − time since point 0`` never overstates what MotoROS still has queued.
    """

    start: float
    """Clock time at which point 0 was accepted."""
    last_time: float
    """Trajectory time of the last accepted point."""
    last_segment: float = 0.0
    """Duration of the last accepted segment."""
    period: float = 0.0
    """The controller's interpolation period (s): how often its pending slot can free."""
    sent_at: float = 0.0
    """Clock time at which the latest offer was sent (once accepted: the last point's)."""
    slot_held: bool = False
    """The last accepted point holds the pending slot (sequence > 0; point 0 does not:
    it starts the trajectory at once, §3.4)."""

    def accepted(self, time_s: float) -> None:
        self.last_segment = time_s - self.last_time
        self.last_time = time_s
        self.slot_held = True

    def relaxed_wait(self, now: float) -> float:
        """How long a BUSY retry may wait without letting the queue run low (0: don't)."""
        spare = self.last_time - (now - self.start) - BUSY_KEEP_AHEAD_S
        return max(0.0, min(spare, self.last_segment, BUSY_RELAXED_MAX_S))

    def first_wait(self, now: float) -> float:
        """How long to wait before the first offer of the next point (:attr:`BusyPolicy.PACED`).

        * One period after the last point was sent: it reached MotoROS one one-way
          delay after that, and the pending slot frees at the first tick after its
          arrival (when the queue has room), at most one period later. So the next
          point arrives in the tick interval right after that tick, the one the
          immediate policy's 0.5–2 ms retries land in: the same tick takes it, and
          points one tick apart still go in one per tick (each sent one period after
          the last, whatever the round trip). A round trip longer than a period
          leaves no wait.
        * With more than :data:`BUSY_KEEP_AHEAD_S` queued, the relaxed wait instead,
          when longer: the time at which the immediate policy's first retry would go
          (its offer at once is a certain BUSY), so the point is accepted at that same
          time.
        """
        if not self.slot_held:
            return 0.0
        return max(self.relaxed_wait(now), self.sent_at + self.period - now)
