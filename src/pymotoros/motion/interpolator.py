"""One group's MotoROS interpolation state and its AddToIncQueue task (§5.2–5.4).

The controller drives it:

* sequence 0 accepted → :meth:`GroupInterpolator.start` (before the checks: MotoROS
  initialises the group first, so even a refused start re-initialises it, §3.4);
* sequence > 0 accepted → :meth:`GroupInterpolator.set_pending` (while
  :attr:`GroupInterpolator.pending` is true the controller answers BUSY);
* every tick → :meth:`GroupInterpolator.fill` (one AddToIncQueue turn), then
  :func:`pymotoros.motion.inc_move` for all groups;
* any queue-clearing trigger → :meth:`GroupInterpolator.clear`.

When a point becomes the segment's end, the whole segment is computed at once
(vectorised, see :mod:`pymotoros.motion.segment`) and handed to the queue as space
allows; a tick then costs a few tuple operations.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.constants import QUEUE_SIZE, SLOTS
from pymotoros.motion.points import ORIGIN, GroupPoint, TrajPoint
from pymotoros.motion.queue import Increment, IncrementQueue
from pymotoros.motion.segment import Segment, compute_segment

logger = logging.getLogger(__name__)


class GroupInterpolator:
    """The per-group state of §5.2 plus the AddToIncQueue task that fills its queue."""

    __slots__ = (
        "_batch",
        "_current",
        "_leftover",
        "_next",
        "_pending",
        "_prev",
        "_segment",
        "axes",
        "q_time",
        "queue",
        "tool",
    )

    def __init__(self, axes: GroupAxes) -> None:
        self.axes = axes
        self.queue = IncrementQueue()
        """The 200-entry increment queue (``count`` for CHECK_QUEUE_CNT)."""
        self.tool = 0
        """Tool for segments interpolated from now on (SELECT_TOOL sets it, §5.8)."""
        self.q_time = 0
        """Time of the last increment IncMove consumed (§5.6)."""
        self._current = ORIGIN
        self._pending: GroupPoint | None = None
        self._segment: Segment | None = None
        self._batch: list[Increment] = []
        self._next = 0
        self._leftover = 0
        self._prev: tuple[int, ...] = (0,) * SLOTS

    # ------------------------------------------------------------------ state

    @property
    def pending(self) -> bool:
        """A point is waiting or still being turned into increments (BUSY while true)."""
        return self._pending is not None

    @property
    def current(self) -> GroupPoint:
        """The interpolation state: the last computed step (time ms, float32 pos/vel)."""
        return self._current

    @property
    def leftover_ms(self) -> int:
        """``timeLeftover_ms``: the first step of the next segment when non-zero."""
        return self._leftover

    @property
    def prev_pulses(self) -> tuple[int, ...]:
        """``prevPulsePos``: the last queued absolute target, 8 slots, controller order."""
        if self._segment is not None and self._next > 0:
            return self._target(self._segment, self._next - 1)
        return self._prev

    # ------------------------------------------------------------------ commands

    def start(self, point: TrajPoint, commanded_pulses: Sequence[int]) -> None:
        """Sequence-0 initialisation (§3.4 step 5.2–5.3).

        The point becomes the current state (time truncated to ms), the leftover is
        cleared, ``q_time`` is the point's time and ``prevPulsePos`` the commanded
        position. The queue is left as it is. A segment still being generated is
        abandoned with its pending point (the real task would carry on from a state
        that no longer matches; the start check refuses such a point anyway unless the
        robot stands still).
        """
        if len(commanded_pulses) != SLOTS:
            raise ValueError(f"commanded pulses need {SLOTS} slots")
        self._drop_segment()
        self._pending = None
        self._current = GroupPoint.from_traj(point, self.axes.float_mode)
        self._leftover = 0
        self.q_time = self._current.time_ms
        self._prev = tuple(int(p) for p in commanded_pulses)

    def set_pending(self, point: TrajPoint) -> None:
        """Accept a sequence > 0 point: it becomes the end of the next segment."""
        if self._pending is not None:
            raise RuntimeError(
                f"group {self.axes.name}: a point is already pending (the controller "
                "must answer BUSY while GroupInterpolator.pending is true)"
            )
        self._pending = GroupPoint.from_traj(point, self.axes.float_mode)

    def clear(self) -> None:
        """Clear the queue and drop the pending point (StopMotion and every clear, §3.6)."""
        self.queue.clear()
        if self._segment is not None:
            self._abort(self._segment)
        self._pending = None

    # ------------------------------------------------------------------ the task

    def fill(self, motion_ready: bool) -> None:
        """One AddToIncQueue turn: queue the pending segment's steps while there is room.

        Not motion-ready: a segment in progress ends where it stands, and a pending
        point that had not started is consumed without increments (as the real loop
        does when its condition fails at once).
        """
        segment = self._segment
        if segment is None:
            pending = self._pending
            if pending is None:
                return
            if not motion_ready:
                self._pending = None
                return
            segment = compute_segment(
                self._current, pending, self._leftover, self._prev, self.tool, self.axes
            )
            if segment is None:
                logger.warning(
                    "group %s: point at %d ms is not after the current time %d ms; "
                    "dropped without increments (MotoROS already answered SUCCESS)",
                    self.axes.name,
                    pending.time_ms,
                    self._current.time_ms,
                )
                self._pending = None
                return
            self._segment = segment
            self._batch = segment.entries
            self._next = 0
        elif not motion_ready:
            self._abort(segment)
            return
        batch = self._batch
        done = self._next
        entries = self.queue._entries  # the deque itself: this runs every tick
        room = QUEUE_SIZE - len(entries)
        if room <= 0:
            return
        stop = done + room
        if stop >= len(batch):
            entries.extend(batch[done:] if done else batch)
            self._finish(segment)
        else:
            entries.extend(batch[done:stop])
            self._next = stop

    # ------------------------------------------------------------------ internals

    def _target(self, segment: Segment, index: int) -> tuple[int, ...]:
        prev = list(self._prev)
        for slot, value in zip(self.axes.axis_slots, segment.targets[index].tolist(), strict=True):
            prev[slot] = value
        return tuple(prev)

    def _finish(self, segment: Segment) -> None:
        self._prev = self._target(segment, len(self._batch) - 1)
        self._current = segment.end
        self._leftover = segment.grid.leftover_ms
        self._drop_segment()
        self._pending = None

    def _abort(self, segment: Segment) -> None:
        """End the segment at the step the task was blocked on (computed, not queued)."""
        blocked = self._next
        if blocked > 0:
            self._prev = self._target(segment, blocked - 1)
        self._current = segment.state_at(blocked)
        last = len(self._batch) - 1
        self._leftover = segment.grid.leftover_ms if blocked == last else 0
        self._drop_segment()
        self._pending = None

    def _drop_segment(self) -> None:
        self._segment = None
        self._batch = []
        self._next = 0
