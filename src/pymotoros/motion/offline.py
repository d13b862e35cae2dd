"""The offline engine: a whole trajectory to increments at once, vectorised.

It produces exactly the entries a :class:`~pymotoros.motion.GroupInterpolator` fed the
same points would queue (the tests check it on random trajectories), without the
queue, the ticks or IncMove: the robot stands at the start point, every point is
accepted or the first refusal raises, and each point is pending as soon as the
previous segment is queued.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from pymotoros.models import FloatMode
from pymotoros.models.rules import MAX_POINT_TIME_S, check_speed, check_start, check_time
from pymotoros.motion.axes import GroupAxes, to_pulses
from pymotoros.motion.batch import BlockDone, batch_increments
from pymotoros.motion.constants import INT32_MAX
from pymotoros.motion.numerics import (
    c_int_array,
    pulses,
)
from pymotoros.motion.points import TrajPoint

logger = logging.getLogger(__name__)

I64Array = npt.NDArray[np.int64]
F64Array = npt.NDArray[np.float64]


def interpolate(
    points: Sequence[TrajPoint], axes: GroupAxes, *, validate: bool = True
) -> tuple[I64Array, I64Array]:
    """(time_ms, increments) of a trajectory; see :func:`interpolate_arrays`."""
    n = axes.num_axes
    if not points:
        raise ValueError("a trajectory needs at least its start point")
    times = np.array([p.time for p in points], dtype=np.float64)
    pos = np.zeros((len(points), n), dtype=np.float64)
    vel = np.zeros((len(points), n), dtype=np.float64)
    for i, p in enumerate(points):
        if len(p.pos) != n or len(p.vel) != n:
            raise ValueError(f"point {i}: group {axes.name} needs {n} positions and velocities")
        pos[i] = p.pos
        vel[i] = p.vel
    return interpolate_arrays(times, pos, vel, axes, validate=validate)


def interpolate_arrays(
    times: F64Array,
    pos: F64Array,
    vel: F64Array,
    axes: GroupAxes,
    *,
    validate: bool = True,
    on_block: BlockDone | None = None,
) -> tuple[I64Array, I64Array]:
    """The increments MotoROS queues for a trajectory given as arrays.

    ``times`` (P,) in s, ``pos`` and ``vel`` (P, num_axes) in ROS order; row 0 is the
    start point (sequence 0) and the robot stands exactly there. Returns ``time_ms``
    (N,) and ``increments`` (N, num_axes), whose column j is controller slot
    ``axes.axis_slots[j]``. With ``validate`` a point MotoROS would refuse raises
    :class:`~pymotoros.errors.TrajectoryRejectedError` (the first one, as a streaming
    client would meet it). Points not after the current one are dropped with a
    warning, as MotoROS drops them. ``on_block`` is told as the leading entries
    become final (see :func:`~pymotoros.motion.batch.batch_increments`), after every
    check has passed.
    """
    mode = axes.float_mode
    n = axes.num_axes
    period = axes.period_ms
    with np.errstate(over="ignore"):
        t32 = np.asarray(times, dtype=np.float64).astype(np.float32)
        p32 = np.asarray(pos, dtype=np.float64).astype(np.float32).reshape(-1, n)
        v32 = np.asarray(vel, dtype=np.float64).astype(np.float32).reshape(-1, n)
    count = t32.shape[0]
    if count == 0 or p32.shape[0] != count or v32.shape[0] != count:
        raise ValueError("times, positions and velocities need the same number of rows (≥ 1)")
    if validate:
        _validate(t32, p32, v32, axes)
    if mode is FloatMode.X87_EXTENDED:
        ms_exact = t32.astype(np.float64) * 1000.0  # exact: 24 × 10 bits
    else:
        ms_exact = (t32 * np.float32(1000.0)).astype(np.float64)
    ms_arr = c_int_array(ms_exact, mode)
    planned = _plan_vectorised(ms_arr, period) or _plan_loop(ms_arr.tolist(), period)
    seg_start, seg_end, seg_first, seg_full, dropped = planned
    if dropped:
        logger.warning(
            "%d point(s) not after the point before them were dropped without increments "
            "(MotoROS accepts and ignores them): %s",
            len(dropped),
            ", ".join(map(str, dropped[:10])) + (" …" if len(dropped) > 10 else ""),
        )

    if not len(seg_start):
        return np.zeros(0, dtype=np.int64), np.zeros((0, n), dtype=np.int64)
    start_target = pulses(p32[0:1], axes.factors_ros, mode)[0, axes.columns]
    s_idx = np.asarray(seg_start, dtype=np.intp)
    e_idx = np.asarray(seg_end, dtype=np.intp)
    return batch_increments(
        np.array((p32[s_idx], v32[s_idx], p32[e_idx], v32[e_idx])),
        ms_arr[s_idx],
        ms_arr[e_idx],
        np.asarray(seg_first, dtype=np.int64),
        np.asarray(seg_full, dtype=np.int64),
        start_target,
        axes,
        on_block=on_block,
    )


_Plan = tuple[
    Sequence[int] | I64Array,
    Sequence[int] | I64Array,
    Sequence[int] | I64Array,
    Sequence[int] | I64Array,
    list[int],
]
"""Per segment: start point index, end point index, first step time, full steps; and
the indices of the dropped points."""


def _plan_loop(ms: list[int], period: int) -> _Plan:
    """The step grids segment by segment, as the real task meets them (§5.4)."""
    seg_start: list[int] = []
    seg_end: list[int] = []
    seg_first: list[int] = []
    seg_full: list[int] = []
    dropped: list[int] = []
    current = 0
    now = ms[0]
    leftover = 0
    for j in range(1, len(ms)):
        end = ms[j]
        if end <= now:
            dropped.append(j)
            continue
        first = now + (leftover or period)
        if first >= end:
            full = 0
            if first > end:
                leftover = first - end
        else:
            full = (end - first + period - 1) // period
            leftover = first + full * period - end
        seg_start.append(current)
        seg_end.append(j)
        seg_first.append(first)
        seg_full.append(full)
        current = j
        now = end
    return seg_start, seg_end, seg_first, seg_full, dropped


def _plan_vectorised(ms: I64Array, period: int) -> _Plan | None:
    """The same grids without a Python loop, or None when the leftover quirk occurs.

    The steps of all segments lie on one grid, ``first step ≡ start + leftover`` (mod
    period): every rule of §5.4 keeps that phase, except the quirk (a leftover-sized
    first step landing exactly on the end keeps its leftover, which moves the grid).
    So the leftover of each segment follows from the phase alone; if some segment
    meets the quirk, the caller runs the loop instead.
    """
    if len(ms) < 2:
        return [], [], [], [], []
    before = np.maximum.accumulate(ms)[:-1]
    accepted = ms[1:] > before
    ends = np.flatnonzero(accepted) + 1
    dropped = (np.flatnonzero(~accepted) + 1).tolist()
    if not len(ends):
        return [], [], [], [], dropped
    starts = np.concatenate(([0], ends[:-1]))
    now = ms[starts]
    end = ms[ends]
    phase = ms[0] % period
    leftover = (phase - now) % period
    first = now + np.where(leftover == 0, period, leftover)
    if np.any((leftover != 0) & (first == end)):
        return None
    full = np.maximum(0, -((first - end) // period))  # ceil((end − first) / period)
    return starts.astype(np.int64), ends.astype(np.int64), first, full.astype(np.int64), dropped


def _validate(
    t32: npt.NDArray[np.float32],
    p32: npt.NDArray[np.float32],
    v32: npt.NDArray[np.float32],
    axes: GroupAxes,
) -> None:
    """Raise for the first point MotoROS would refuse; warn about the speed quirk."""

    def point(i: int) -> TrajPoint:
        return TrajPoint(float(t32[i]), tuple(p32[i].tolist()), tuple(v32[i].tolist()))

    start = point(0)
    commanded = to_pulses(start.pos, axes)
    for refusal in (check_time(start), check_start(start, commanded, axes)):
        if refusal is not None:
            raise refusal.error(0)
    if t32.shape[0] == 1:
        return
    limit = np.array(axes.max_speed[: axes.num_axes], dtype=np.float64)
    speed = np.abs(v32[1:].astype(np.float64))
    with np.errstate(invalid="ignore"):
        bad_number = ~(speed <= INT32_MAX)
        whole = np.trunc(np.where(bad_number, 0.0, speed))
        too_fast = (whole > limit) | bad_number
        late = ~(t32[1:] < MAX_POINT_TIME_S)
    failing = too_fast.any(axis=1) | late
    if failing.any():
        i = int(np.argmax(failing)) + 1
        p = point(i)
        refusal = check_time(p) or check_speed(p, axes)
        if refusal is None:  # pragma: no cover - the vectorised test and the checks disagree
            raise RuntimeError(f"point {i} failed the vectorised check but not check_speed")
        raise refusal.error(i)
    quirk = (speed > limit).any(axis=1)
    if quirk.any():
        i = int(np.argmax(quirk)) + 1
        j = int(np.argmax(speed[i - 1] > limit))
        logger.warning(
            "%d point(s) have a velocity above the axis maximum that MotoROS accepts because "
            "its speed check truncates |v| first; the first is point %d, %s at %.6g rad/s "
            "(limit %.6g rad/s)",
            int(quirk.sum()),
            i,
            axes.joint_name(j),
            float(speed[i - 1, j]),
            float(limit[j]),
        )
