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
the segment in pieces of :data:`PIECE_ENTRIES` entries, the next one when the queue
has taken the last (so no point, however far away, makes a tick do more work), and
queues them as the real task does, within the 200 limit; their pulses are computed
when IncMove reaches them: the oldest piece alone when it has
:data:`FRONT_MIN_ENTRIES` entries or more (:func:`pymotoros.motion.batch.segment_targets`,
so that no tick pays for a whole queue), otherwise every queued piece together,
vectorised (:func:`pymotoros.motion.batch.queued_targets`). The results are those of
the step-by-step loop; a tick costs a few tuple operations. A segment computed on its
own (the queue ran dry) with few steps is done in plain Python.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Iterable, Sequence
from itertools import repeat
from operator import sub
from typing import Final

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.motion.axes import GroupAxes
from pymotoros.motion.batch import queued_targets, segment_targets
from pymotoros.motion.constants import INT32_MAX, INT32_MIN, QUEUE_SIZE, SLOTS
from pymotoros.motion.numerics import (
    coefficients_x87_exact,
    coefficients_x87_scalar,
    f32,
    f32_tuple,
    positions_x87_scalar,
    pulse,
    small_segment_x87,
)
from pymotoros.motion.one_segment import compute_segment
from pymotoros.motion.points import ORIGIN, GroupPoint, TrajPoint
from pymotoros.motion.queue import Increment, IncrementQueue
from pymotoros.motion.segment import Grid, plan_grid

logger = logging.getLogger(__name__)

F32Array = npt.NDArray[np.float32]
I64Array = npt.NDArray[np.int64]

SMALL_SEGMENT_STEPS: Final = 8
"""A segment computed on its own with at most this many steps (besides the last) is
done in plain Python: below that, numpy's per-call cost exceeds the arithmetic."""


SMALL_GRID_CACHE: Final = 4096
"""Most (segment length, first step, steps, period) keys :func:`_small_grid` remembers.
Points at a fixed spacing repeat a handful of keys; the cap only bounds what a client
sending arbitrary times can make it hold (a few hundred KiB)."""


@functools.lru_cache(maxsize=SMALL_GRID_CACHE)
def _small_grid(
    length_ms: int, first_ms: int, steps: int, period_ms: int
) -> tuple[float, tuple[float, ...]]:
    """T and the τ of each step, as float32, of a small segment of ``length_ms`` whose
    first step is ``first_ms`` after its start (x87 plain-Python path,
    :meth:`GroupInterpolator._compute_small`). They depend on these integers alone, and
    at a fixed spacing every segment has one of a few, so a tick looks them up instead
    of rounding them again: a memo of a pure function, bounded, never state."""
    return (
        f32(length_ms / 1000),
        f32_tuple([(first_ms + period_ms * k) / 1000 for k in range(steps)], steps),
    )


_INT32_LOW: Final = float(INT32_MIN) - 1.0
_INT32_HIGH: Final = float(INT32_MAX) + 1.0
"""Products strictly between these truncate to an int32 (C's conversion is defined)."""

FRONT_MIN_ENTRIES: Final = 20
"""The oldest queued segment is computed alone (:meth:`GroupInterpolator._compute_front`)
from this many entries (points 80 ms or more apart at 4 ms); shorter ones with all the
planned segments at once. Alone, a segment costs ~50 µs whatever its length, against
~0.75 µs per entry in a full batch (bench/bench_tick_spikes.py, issue 13's second
round): spread over fewer than 20 ticks that would cost virtual time more than 2 µs a
tick, taking 50 ms spacing under 500× real time (bench/bench_controller.py --reference
batch). Points that dense keep the batch and its rarer, longer tick."""

PIECE_ENTRIES: Final = QUEUE_SIZE
"""Entries of a segment planned (and later computed) at a time. A segment is cut into
pieces of this many entries, each planned when the queue has taken the previous one,
so the work and memory of a tick do not depend on the segment's length: a legal point
14,400 s away (§3.4's limit) is 3.6 million steps at 4 ms."""


class PlannedSegment:
    """A piece of a segment whose grid is known; its pulses are computed on demand.

    The piece holds entries ``step0`` … ``step0 + count − 1`` of the segment (entry
    ``grid.full_steps`` is the end point); ``start``, ``end`` and ``grid`` are the whole
    segment's.
    """

    __slots__ = (
        "chain",
        "end",
        "entries",
        "grid",
        "last",
        "leftover_before",
        "offset",
        "start",
        "step0",
        "steps",
        "tool",
    )

    def __init__(
        self,
        start: GroupPoint,
        end: GroupPoint,
        grid: Grid,
        tool: int,
        leftover: int,
        step0: int = 0,
    ) -> None:
        self.start = start
        self.end = end
        self.grid = grid
        self.tool = tool
        self.leftover_before = leftover
        self.step0 = step0
        total = grid.full_steps + 1
        stop = min(step0 + PIECE_ENTRIES, total)
        self.last = stop == total
        """The piece ends with the segment's end point."""
        self.steps = stop - step0 - 1 if self.last else stop - step0
        """Interpolated steps in the piece (the end point excluded)."""
        self.entries: list[Increment] | None = None
        self.chain: Sequence[tuple[int, ...]] | npt.NDArray[np.int64] = ()
        """Once computed: 8-slot absolute targets; row ``offset`` is prevPulsePos before
        the segment, row ``offset + 1 + i`` the target of entry i (shared by the
        segments computed together)."""
        self.offset = 0

    @property
    def count(self) -> int:
        """Entries in the piece."""
        return self.steps + 1 if self.last else self.steps

    def next_piece(self) -> PlannedSegment:
        """The piece after this one (this one must not be the last)."""
        return PlannedSegment(
            self.start,
            self.end,
            self.grid,
            self.tool,
            self.leftover_before,
            self.step0 + self.count,
        )

    def target(self, index: int) -> tuple[int, ...]:
        """prevPulsePos once entry ``index`` of the piece is queued (8 slots); -1: before
        the piece."""
        row = self.chain[self.offset + 1 + index]
        return row if isinstance(row, tuple) else tuple(row.tolist())


class GroupInterpolator:
    """The per-group state of §5.2 plus the AddToIncQueue task that fills its queue."""

    __slots__ = (
        "_active",
        "_chain_prev",
        "_current",
        "_leftover",
        "_next",
        "_pending",
        "_plain_slots",
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
        self.queue = IncrementQueue(self._compute, self._compute_front)
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
        self._plain_slots = axes.ros_to_slot[: axes.num_axes] == tuple(range(axes.num_axes))
        """ROS index j is controller slot j for every axis (all but 7-axis arms)."""

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
        return segment.target(index)

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
        self.set_pending_point(GroupPoint.from_traj(point, self.axes.float_mode))

    def set_pending_point(self, point: GroupPoint) -> None:
        """:meth:`set_pending` for a point already in its float32 form."""
        if self._pending is not None:
            raise RuntimeError(
                f"group {self.axes.name}: a point is already pending (the controller "
                "must answer BUSY while GroupInterpolator.pending is true)"
            )
        self._pending = point

    def clear(self) -> None:
        """Clear the queue and drop the pending point (StopMotion and every clear, §3.6)."""
        if self._active is not None:
            self._abort(self._active)
        self._compute()
        self.queue.clear()
        self._pending = None

    def end_task(self) -> None:
        """The AddToIncQueue task is deleted (the motion connection closed, §2.2): the
        segment in progress ends at the step the task stood on, the pending point is
        dropped; the queue is left as it is (the next IncMove task executes it)."""
        if self._active is not None:
            self._abort(self._active)
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
        done = self._next
        queue = self.queue
        while True:
            count = segment.count
            stop = queue.queue_segment(segment, done, count)
            if stop == done:  # the queue is full
                return
            self._prev_at = (segment, stop - 1)
            if stop < count:
                self._next = stop
                return
            if segment.last:
                self._current = segment.end
                self._leftover = segment.grid.leftover_ms
                self._active = None
                self._pending = None
                return
            # The piece is queued: plan the next one (at most PIECE_ENTRIES entries).
            segment = segment.next_piece()
            self._uncomputed.append(segment)
            self._active = segment
            self._next = done = 0

    # ------------------------------------------------------------------ internals

    def _abort(self, segment: PlannedSegment) -> None:
        """End the segment at the step the task was blocked on (computed, not queued)."""
        self._compute()
        blocked = segment.step0 + self._next  # the entry's index in the whole segment
        if blocked == segment.grid.full_steps:
            self._current = segment.end
            self._leftover = segment.grid.leftover_ms
        else:
            # Only the blocked step is computed: the segment may be millions of steps.
            one = compute_segment(
                segment.start,
                segment.end,
                segment.leftover_before,
                segment.target(-1),
                segment.tool,
                self.axes,
                only=blocked,
            )
            if one is None:  # pragma: no cover - a planned segment always has steps
                raise RuntimeError("planned segment without steps")
            self._current = one.state_at(0)
            self._leftover = 0
        self._chain_prev = self.prev_pulses  # the steps after the blocked one never existed
        self._active = None
        self._pending = None

    def _targets(
        self, rows: Iterable[Sequence[float]], prev: tuple[int, ...]
    ) -> list[tuple[int, ...]]:
        """prevPulsePos after each row of float32 positions (ROS order, ``num_axes``
        values): the pulses of the axes' slots, the other slots as in ``prev``."""
        axes = self.axes
        mode = axes.float_mode
        factors = axes.factors_ros_list
        out: list[tuple[int, ...]] = []
        if mode is FloatMode.X87_EXTENDED and self._plain_slots:
            # Slots 0 … n − 1 in ROS order (every group but a 7-axis arm): the x87
            # truncates the exact float64 product (c_int inlined; out of range → pulse()).
            rest = prev[axes.num_axes :]
            for row in rows:
                products = [x * f for x, f in zip(row, factors, strict=True)]
                if min(products) > _INT32_LOW and max(products) < _INT32_HIGH:
                    try:
                        out.append((*map(int, products), *rest))
                        continue
                    except ValueError:  # a NaN that min() and max() passed over
                        pass
                out.append(
                    (
                        *(
                            int(p) if _INT32_LOW < p < _INT32_HIGH else pulse(x, f, mode)
                            for p, x, f in zip(products, row, factors, strict=True)
                        ),
                        *rest,
                    )
                )
            return out
        slots = axes.ros_to_slot[: axes.num_axes]
        before = prev
        for row in rows:
            spread = list(before)
            for x, f, slot in zip(row, factors, slots, strict=True):
                spread[slot] = pulse(x, f, mode)
            before = tuple(spread)
            out.append(before)
        return out

    def _store_small(
        self,
        segment: PlannedSegment,
        prev: tuple[int, ...],
        times: list[int],
        rows: list[Sequence[float]],
    ) -> None:
        """Queue entries of a segment computed in plain Python (targets from ``rows``)."""
        chain = [prev, *self._targets(rows, prev)]
        tool = segment.tool
        new = tuple.__new__
        segment.entries = [
            new(Increment, (time_ms, tuple(map(sub, after, before)), tool))
            for time_ms, before, after in zip(times, chain, chain[1:], strict=False)
        ]
        segment.chain = chain
        segment.offset = 0
        self._chain_prev = chain[-1]

    def _store_end_x87(self, segment: PlannedSegment, prev: tuple[int, ...], n: int) -> None:
        """:meth:`_store_small` of a piece that is only its end point, x87, slots in ROS
        order: the one entry a tick queues when points come every period.

        The same target as :meth:`_targets` (each product truncated, or :func:`pulse`
        out of the int32 range) without its per-row generality; the plain-Python
        segment tests compare it with the numpy kernels.
        """
        end = segment.end
        products = [x * f for x, f in zip(end.pos, self.axes.factors_ros_list, strict=False)]
        target: tuple[int, ...]
        try:  # not contextlib.suppress: its context manager costs more than the rest here
            if not (min(products) > _INT32_LOW and max(products) < _INT32_HIGH):
                raise ValueError
            target = (*map(int, products), *prev[n:])
        except ValueError:  # out of the int32 range, or a NaN that min() and max() passed
            target = self._targets([end.pos[:n]], prev)[0]
        segment.entries = [
            tuple.__new__(Increment, (end.time_ms, tuple(map(sub, target, prev)), segment.tool))
        ]
        segment.chain = (prev, target)
        segment.offset = 0
        self._chain_prev = target

    def _compute_small(self, segment: PlannedSegment, prev: tuple[int, ...]) -> bool:
        """The last piece of a segment with at most :data:`SMALL_SEGMENT_STEPS` steps in
        plain Python; False if the numpy kernels must do it (FS100, untame values, more
        steps, or a value the float64 checks cannot vouch for).

        A piece that is only the end point (points as dense as the period) needs no
        interpolation: its target is the end position in pulses, in either float mode.
        """
        full = segment.steps
        if full > SMALL_SEGMENT_STEPS or not segment.last:
            return False
        axes = self.axes
        n = axes.num_axes
        end = segment.end
        if not full:
            if axes.float_mode is FloatMode.X87_EXTENDED and self._plain_slots:
                self._store_end_x87(segment, prev, n)
            else:
                self._store_small(segment, prev, [end.time_ms], [end.pos[:n]])
            return True
        start = segment.start
        if axes.float_mode is not FloatMode.X87_EXTENDED or not (start.tame and end.tame):
            return False
        s_ms = start.time_ms
        x0, v0 = start.pos[:n], start.vel[:n]
        x1, v1 = end.pos[:n], end.vel[:n]
        period = axes.period_ms
        first = segment.grid.first_ms + period * segment.step0
        times = [first + period * k for k in range(full)]
        duration, taus = _small_grid(end.time_ms - s_ms, first - s_ms, full, period)
        # The fused float64 kernel where its error bounds vouch for the x87's values,
        # else the two-pass form (coefficients, then positions); else the numpy kernels.
        rows: list[Sequence[float]] | None
        rows = small_segment_x87(x0, v0, x1, v1, duration, taus)  # type: ignore[assignment]
        if rows is None:
            coef = coefficients_x87_scalar(x0, v0, x1, v1, duration) or coefficients_x87_exact(
                x0, v0, x1, v1, duration
            )
            h1 = [c / 2 for c in coef[:n]]
            rows = positions_x87_scalar(x0, v0, h1, coef[n:], taus, duration)  # type: ignore[assignment]
            if rows is None:
                return False
        rows.append(x1)
        times.append(end.time_ms)
        self._store_small(segment, prev, times, rows)
        return True

    def _compute(self) -> None:
        """Compute the pulses of every planned segment not computed yet, in order."""
        segments = self._uncomputed
        if not segments:
            return
        self._uncomputed = []
        axes = self.axes
        prev = self._chain_prev
        if len(segments) == 1 and self._compute_small(segments[0], prev):
            return
        n = axes.num_axes
        count = len(segments)
        raw = b"".join([p for s in segments for p in (s.start.packed(), s.end.packed())])
        rows = np.frombuffer(raw, dtype=np.float32).reshape(count, 4, SLOTS)[:, :, :n]
        period = axes.period_ms
        grids = [
            (
                s.start.time_ms,
                s.end.time_ms,
                s.grid.first_ms + period * s.step0,
                s.steps,
                s.last,
            )
            for s in segments
        ]
        times, targets = queued_targets(rows.transpose(1, 0, 2), grids, axes)
        self._store(segments, times, targets, prev)

    def _compute_front(self) -> None:
        """Compute the oldest planned segment not computed yet, alone: what IncMove
        needs next (the queue's ``due``), so that the pulses of a full queue are not all
        paid in one tick.

        It goes to :func:`segment_targets`, whose values are those of
        :func:`queued_targets` (``tests/motion/test_front_path.py`` compares them);
        points that are not tame (NaN, infinities, huge values) take the general kernel.
        A segment of fewer than :data:`FRONT_MIN_ENTRIES` entries is computed with every
        planned one (:meth:`_compute`).
        """
        segments = self._uncomputed
        if not segments:
            return
        segment = segments[0]
        if segment.count < FRONT_MIN_ENTRIES:
            self._compute()
            return
        del segments[0]
        prev = self._chain_prev
        axes = self.axes
        n = axes.num_axes
        start, end = segment.start, segment.end
        period = axes.period_ms
        first = segment.grid.first_ms + period * segment.step0
        steps = segment.steps
        times = list(range(first, first + period * steps, period))
        if segment.last:
            times.append(end.time_ms)
        if start.tame and end.tame:
            targets = segment_targets(
                (start.pos[:n], start.vel[:n]),
                (end.pos[:n], end.vel[:n]),
                end.time_ms - start.time_ms,
                first - start.time_ms,
                steps,
                segment.last,
                axes,
            )
        else:
            raw = start.packed() + end.packed()
            rows = np.frombuffer(raw, dtype=np.float32).reshape(4, 1, SLOTS)[:, :, :n]
            grid = (start.time_ms, end.time_ms, first, steps, segment.last)
            times, targets = queued_targets(rows, [grid], axes)
        self._store([segment], times, targets, prev)

    def _store(
        self,
        segments: list[PlannedSegment],
        times: list[int],
        targets: I64Array,
        prev: tuple[int, ...],
    ) -> None:
        """Give computed segments their entries from the absolute ``targets`` of their
        entries in order (columns as :func:`queued_targets`'s); ``prev`` is prevPulsePos
        before the first."""
        axes = self.axes
        n = axes.num_axes
        # Row 0: prevPulsePos before the first segment; the slots without an axis keep it.
        chain = np.empty((len(times) + 1, SLOTS), dtype=np.int64)
        chain[:] = prev
        if axes.contiguous:
            chain[1:, :n] = targets
        else:
            chain[1:, axes.axis_slots_array] = targets
        increments = map(tuple, (chain[1:] - chain[:-1]).tolist())
        tool = segments[0].tool
        tools: Iterable[int] = repeat(tool)
        if any(s.tool != tool for s in segments):
            tools = [s.tool for s in segments for _ in range(s.count)]
        # tuple.__new__ builds each NamedTuple without a Python-level call
        entries = list(
            map(tuple.__new__, repeat(Increment), zip(times, increments, tools, strict=False))
        )
        lo = 0
        for segment in segments:
            hi = lo + segment.count
            segment.chain = chain
            segment.offset = lo
            segment.entries = entries[lo:hi]
            lo = hi
        self._chain_prev = tuple(chain[-1].tolist())
