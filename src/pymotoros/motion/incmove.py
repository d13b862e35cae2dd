"""The IncMove task: one increment per group per tick, partial steps re-joined (§5.6)."""

from __future__ import annotations

from collections.abc import Sequence
from operator import add

from pymotoros.motion.interpolator import GroupInterpolator
from pymotoros.motion.queue import ZERO_PULSES, Increment


def inc_move(groups: Sequence[GroupInterpolator]) -> tuple[Increment, ...] | None:
    """One IncMove turn over every group, or None when every queue is empty.

    Per group: pop the oldest entry; while the next one ends within one period of the
    group's ``q_time`` (the time reached on the previous tick) and has the same tool,
    pop it too and add its pulses, so that a partial end-of-segment step and the next
    segment's leftover step move in one tick; then ``q_time`` becomes the time
    reached. A group with an empty queue gets zero pulses and tool 0.

    The caller checks the rest of the send condition (motion-ready, no stop pending)
    and adds each group's pulses to its commanded position. The v1.9.12 compensation
    for a controller whose FSU clips the increments is not in this function: it needs
    the controller's answer (which pulses it executed), so the controller's IncMove
    task does it (``pymotoros.controller.incmove_task``, §5.6 step 3); on a controller
    that executes every pulse it changes nothing.
    """
    out: list[Increment] = []
    moved = False
    for group in groups:
        entries = group.queue.due()
        if not entries:
            out.append(Increment(group.q_time, ZERO_PULSES, 0))
            continue
        moved = True
        entry = entries.popleft()
        if entries:
            q_time = group.q_time
            limit = q_time + group.axes.period_ms
            nxt = entries[0]
            if q_time <= nxt.time_ms <= limit and nxt.tool == entry.tool:
                tool = entry.tool
                pulses = entry.pulses
                while True:
                    entries.popleft()
                    pulses = tuple(map(add, pulses, nxt.pulses))
                    time_ms = nxt.time_ms
                    if not entries:
                        break
                    nxt = entries[0]
                    if not (q_time <= nxt.time_ms <= limit and nxt.tool == tool):
                        break
                entry = Increment(time_ms, pulses, tool)
        group.q_time = entry.time_ms
        out.append(entry)
    return tuple(out) if moved else None


def add_pulses(position: Sequence[int], increment: Sequence[int]) -> tuple[int, ...]:
    """A commanded pulse position advanced by one increment (both 8 slots)."""
    return tuple(map(add, position, increment))
