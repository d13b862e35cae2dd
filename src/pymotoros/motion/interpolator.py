"""One group's MotoROS interpolation state and its AddToIncQueue task (§5.2–5.4).

The controller drives it:

* sequence 0 accepted → :meth:`GroupInterpolator.start` (before the checks: MotoROS
  initialises the group first, so even a refused start re-initialises it, §3.4);
* sequence > 0 accepted → :meth:`GroupInterpolator.set_pending` (while
  :attr:`GroupInterpolator.pending` is true the controller answers BUSY);
* every tick → :meth:`GroupInterpolator.fill` (one AddToIncQueue turn), then
  :func:`pymotoros.motion.inc_move` for all groups;
* any queue-clearing trigger → :meth:`GroupInterpolator.clear`.

A segment's step grid, and so the number and times of its entries, is integer
arithmetic; its pulses are not needed before IncMove reaches them. So ``fill`` plans
the segment and queues its entries at once (as the real task does, within the 200
limit), and the pulses of all queued segments are computed together, vectorised
(:func:`pymotoros.motion.batch.batch_targets`), when the first of them is due. The
results are those of the step-by-step loop; a tick costs a few tuple operations.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.batch import batch_targets
from pymotoros.motion.constants import QUEUE_SIZE, SLOTS
from pymotoros.motion.points import ORIGIN, GroupPoint, TrajPoint
from pymotoros.motion.queue import Increment, IncrementQueue
from pymotoros.motion.segment import Grid, compute_segment, make_entries, plan_grid

logger = logging.getLogger(__name__)


class PlannedSegment:
    """A segment whose grid is known; its pulses are computed on demand."""

    __slots__ = (
        "end",
        "entries",
        "grid",
        "leftover_before",
        "prev_before",
        "start",
        "targets",
        "tool",
    )

    def __init__(
        self, start: GroupPoint, end: GroupPoint, grid: Grid, tool: int, leftover: int
    ) -> None:
        self.start = start
        self.end = end
        self.grid = grid
        self.tool = tool
        self.leftover_before = leftover
        self.entries: list[Increment] | None = None
        self.prev_before: tuple[int, ...] = ()
        """prevPulsePos before the segment (known once computed)."""
        self.targets: list[list[int]] = []
        """Absolute target of each entry, valid slots in ascending order."""

    @property
    def count(self) -> int:
        return self.grid.full_steps + 1

    def target(self, index: int, axes: GroupAxes) -> tuple[int, ...]:
        """prevPulsePos once entry ``index`` is queued (8 slots)."""
        out = list(self.prev_before)
        for slot, value in zip(axes.axis_slots, self.targets[index], strict=True):
            out[slot] = value
        return tuple(out)


class GroupInterpolator:
    """The per-group state of §5.2 plus the AddToIncQueue task that fills its queue."""

    __slots__ = (
        "_active",
        "_chain_prev",
        "_current",
        "_leftover",
        "_next",
        "_pending",
        "_prev",
        "_prev_at",
        "_uncomputed",
        "axes",
        "q_time",
        "queue",
        "tool",
    )

    def __init__(self, axes: GroupAxes) -> None:
        self.axes = axes
        self.queue = IncrementQueue(self._compute)
        """The 200-entry increment queue (``count`` for CHECK_QUEUE_CNT)."""
        self.tool = 0
        """Tool for segments interpolated from now on (SELECT_TOOL sets it, §5.8)."""
        self.q_time = 0
        """Time of the last increment IncMove consumed (§5.6)."""
        self._current = ORIGIN
        self._pending: GroupPoint | None = None
        self._leftover = 0
        self._active: PlannedSegment | None = None
        """The segment being queued (its end is the pending point)."""
        self._next = 0
        """Next entry of the active segment to queue."""
        self._uncomputed: list[PlannedSegment] = []
        self._chain_prev: tuple[int, ...] = (0,) * SLOTS
        """prevPulsePos after the last computed segment (or the start)."""
        self._prev: tuple[int, ...] = (0,) * SLOTS
        self._prev_at: tuple[PlannedSegment, int] | None = None
        """The entry whose target is prevPulsePos, or None: then it is ``_prev``."""

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
        if self._prev_at is None:
            return self._prev
        self._compute()
        segment, index = self._prev_at
        return segment.target(index, self.axes)

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
        self._compute()  # entries still queued keep the pulses they were planned with
        self._active = None
        self._pending = None
        self._current = GroupPoint.from_traj(point, self.axes.float_mode)
        self._leftover = 0
        self.q_time = self._current.time_ms
        self._prev = self._chain_prev = tuple(int(p) for p in commanded_pulses)
        self._prev_at = None

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
        if self._active is not None:
            self._abort(self._active)
        self._compute()
        self.queue.clear()
        self._pending = None

    # ------------------------------------------------------------------ the task

    def fill(self, motion_ready: bool) -> None:
        """One AddToIncQueue turn: queue the pending segment's steps while there is room.

        Not motion-ready: a segment in progress ends where it stands, and a pending
        point that had not started is consumed without increments (as the real loop
        does when its condition fails at once).
        """
        segment = self._active
        if segment is None:
            pending = self._pending
            if pending is None:
                return
            if not motion_ready:
                self._pending = None
                return
            current = self._current
            if pending.time_ms <= current.time_ms:
                logger.warning(
                    "group %s: point at %d ms is not after the current time %d ms; "
                    "dropped without increments (MotoROS already answered SUCCESS)",
                    self.axes.name,
                    pending.time_ms,
                    current.time_ms,
                )
                self._pending = None
                return
            grid = plan_grid(current.time_ms, pending.time_ms, self._leftover, self.axes.period_ms)
            segment = PlannedSegment(current, pending, grid, self.tool, self._leftover)
            self._uncomputed.append(segment)
            self._active = segment
            self._next = 0
        elif not motion_ready:
            self._abort(segment)
            return
        # The queue's own fields: this runs every tick, usually to add one entry.
        queue = self.queue
        room = QUEUE_SIZE - len(queue._entries) - queue._lazy_count
        if room <= 0:
            return
        done = self._next
        count = segment.grid.full_steps + 1
        stop = count if done + room >= count else done + room
        lazy = queue._lazy
        if lazy and lazy[-1][0] is segment:  # extend the chunk queued on the last tick
            lazy[-1] = (segment, lazy[-1][1], stop)
        else:
            lazy.append((segment, done, stop))
        queue._lazy_count += stop - done
        self._prev_at = (segment, stop - 1)
        if stop == count:
            self._current = segment.end
            self._leftover = segment.grid.leftover_ms
            self._active = None
            self._pending = None
        else:
            self._next = stop

    # ------------------------------------------------------------------ internals

    def _abort(self, segment: PlannedSegment) -> None:
        """End the segment at the step the task was blocked on (computed, not queued)."""
        self._compute()
        blocked = self._next
        full = compute_segment(
            segment.start,
            segment.end,
            segment.leftover_before,
            segment.prev_before,
            segment.tool,
            self.axes,
        )
        if full is None:  # pragma: no cover - a planned segment always has steps
            raise RuntimeError("planned segment without steps")
        self._current = full.state_at(blocked)
        self._leftover = segment.grid.leftover_ms if blocked == segment.count - 1 else 0
        self._chain_prev = self.prev_pulses  # the steps after the blocked one never existed
        self._active = None
        self._pending = None

    def _compute(self) -> None:
        """Compute the pulses of every planned segment not computed yet, in order."""
        segments = self._uncomputed
        if not segments:
            return
        self._uncomputed = []
        axes = self.axes
        n = axes.num_axes
        prev = self._chain_prev
        if len(segments) == 1:
            only = segments[0]
            single = compute_segment(
                only.start, only.end, only.leftover_before, prev, only.tool, axes
            )
            if single is None:  # pragma: no cover - a planned segment always has steps
                raise RuntimeError("planned segment without steps")
            only.prev_before = prev
            only.entries = single.entries
            only.targets = single.targets.tolist()
            self._chain_prev = only.target(only.count - 1, axes)
            return
        rows = np.array(
            [(s.start.pos[:n], s.start.vel[:n], s.end.pos[:n], s.end.vel[:n]) for s in segments],
            dtype=np.float32,
        ).transpose(1, 0, 2)
        ints = np.array(
            [
                (s.start.time_ms, s.end.time_ms, s.grid.first_ms, s.grid.full_steps)
                for s in segments
            ],
            dtype=np.int64,
        )
        times, targets = batch_targets(rows, ints[:, 0], ints[:, 1], ints[:, 2], ints[:, 3], axes)
        chain = np.empty((len(times) + 1, n), dtype=np.int64)
        chain[0] = axes.take(prev)
        chain[1:] = targets
        tools: list[int] = []
        for segment in segments:
            tools += [segment.tool] * segment.count
        entries = make_entries(times.tolist(), chain, tools, axes)
        target_rows = targets.tolist()
        lo = 0
        for segment in segments:
            hi = lo + segment.count
            segment.prev_before = prev
            segment.targets = target_rows[lo:hi]
            segment.entries = entries[lo:hi]
            prev = segment.target(segment.count - 1, axes)
            lo = hi
        self._chain_prev = prev
