"""The tick-by-tick engine: offline equality, the 200-entry queue, IncMove's merge."""

from __future__ import annotations

import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.motion import (
    QUEUE_SIZE,
    GroupAxes,
    GroupInterpolator,
    Increment,
    TrajPoint,
    add_pulses,
    inc_move,
    interpolate,
    to_pulses,
)

from .helpers import axes_for, still
from .strategies import trajectories

LONG_SEGMENTS = st.one_of(
    st.integers(1, 1500).map(lambda k: k / 1000),  # up to 375 entries: beyond the queue
    st.sampled_from([0.025, 0.0, -0.002]),
)


def queued_by_ticks(points: list[TrajPoint], axes: GroupAxes) -> list[tuple[int, list[int]]]:
    """Stream the points as a client would (next point as soon as not BUSY) and record
    every entry in the order the task queued it, taking one entry out per tick."""
    g = GroupInterpolator(axes)
    g.start(points[0], to_pulses(points[0].pos, axes))
    rest = list(points[1:])
    seen: list[tuple[int, list[int]]] = []
    for _ in range(100_000):
        if rest and not g.pending:
            g.set_pending(rest.pop(0))
        g.fill(True)
        assert g.queue.count <= QUEUE_SIZE
        if g.queue.count:
            entry = g.queue.pop()
            seen.append((entry.time_ms, [entry.pulses[s] for s in axes.axis_slots]))
        elif not rest and not g.pending:
            return seen
    raise AssertionError("did not finish")


def busy(g: GroupInterpolator) -> bool:
    return g.pending


def offline(points: list[TrajPoint], axes: GroupAxes) -> list[tuple[int, list[int]]]:
    times, incs = interpolate(points, axes, validate=False)
    return list(zip(times.tolist(), incs.tolist(), strict=True))


@settings(max_examples=60, deadline=None)
@given(
    trajectories(durations=LONG_SEGMENTS),
    st.sampled_from([("hc10", "yrc1000"), ("hc10", "fs100"), ("sia20d", "dx100")]),
)
def test_offline_equals_tick_by_tick(points: list[TrajPoint], cell: tuple[str, str]) -> None:
    axes = axes_for(*cell)
    n = axes.num_axes
    points = [
        TrajPoint(
            p.time, p.pos[:n] + (0.1,) * (n - len(p.pos)), p.vel[:n] + (0.0,) * (n - len(p.vel))
        )
        for p in points
    ]
    assert queued_by_ticks(points, axes) == offline(points, axes)


def test_queue_holds_200_and_the_point_stays_pending(hc10: GroupAxes) -> None:
    g = GroupInterpolator(hc10)
    start = still(0.0, (0.0,) * 6)
    g.start(start, to_pulses(start.pos, hc10))
    g.set_pending(still(1.0, (0.5,) * 6))  # 1 s: 249 or 250 entries
    g.fill(True)
    assert g.queue.count == QUEUE_SIZE
    assert g.pending  # a new point would get BUSY
    with pytest.raises(RuntimeError, match="already pending"):
        g.set_pending(still(2.0, (0.6,) * 6))
    g.fill(True)  # no room: nothing happens
    assert g.queue.count == QUEUE_SIZE
    ticks = 0
    while busy(g):
        inc_move([g])
        g.fill(True)
        ticks += 1
        assert g.queue.count <= QUEUE_SIZE
    assert ticks == 50  # 250 entries: 200 at once, then one per tick
    assert g.current.time_ms == 1000


def test_t_le_zero_points_are_dropped_with_a_warning(
    hc10: GroupAxes, caplog: pytest.LogCaptureFixture
) -> None:
    g = GroupInterpolator(hc10)
    start = still(0.5, (0.0,) * 6)
    g.start(start, to_pulses(start.pos, hc10))
    g.set_pending(still(0.5, (0.1,) * 6))
    with caplog.at_level(logging.WARNING):
        g.fill(True)
    assert not g.pending
    assert g.queue.count == 0
    assert "dropped" in caplog.text
    assert g.current.time_ms == 500
    assert float(g.current.pos[0]) == 0.0


def _two_25ms_segments(axes: GroupAxes, *, second_late: bool) -> list[Increment]:
    g = GroupInterpolator(axes)
    pts = [still(0.0, (0.0,) * 6), still(0.0255, (0.01,) * 6), still(0.0505, (0.02,) * 6)]
    g.start(pts[0], to_pulses(pts[0].pos, axes))
    g.set_pending(pts[1])
    ticks: list[Increment] = []
    pending = [pts[2]]
    for tick in range(20):
        if pending and not g.pending and (not second_late or tick >= 7):
            g.set_pending(pending.pop())
        g.fill(True)
        out = inc_move([g])
        if out is not None:
            ticks.append(out[0])
    return ticks


def test_inc_move_joins_the_partial_step_with_the_next_leftover_step(hc10: GroupAxes) -> None:
    ticks = _two_25ms_segments(hc10, second_late=False)
    # queued: 4..24, 25 | 28, 32 … 48, 50. The 1 ms step (25) and the 3 ms step (28)
    # move in one tick, so 14 entries take 13 ticks.
    assert [t.time_ms for t in ticks] == [4, 8, 12, 16, 20, 24, 28, 32, 36, 40, 44, 48, 50]
    offline_times, offline_incs = interpolate(
        [still(0.0, (0.0,) * 6), still(0.0255, (0.01,) * 6), still(0.0505, (0.02,) * 6)], hc10
    )
    assert offline_times.tolist()[6:8] == [25, 28]
    merged = [int(offline_incs[6, k] + offline_incs[7, k]) for k in range(6)]
    assert list(ticks[6].pulses[:6]) == merged
    total = [sum(t.pulses[k] for t in ticks) for k in range(8)]
    assert total == [int(offline_incs[:, k].sum()) for k in range(6)] + [0, 0]


def test_no_merge_when_the_next_segment_is_not_queued_yet(hc10: GroupAxes) -> None:
    ticks = _two_25ms_segments(hc10, second_late=True)
    times = [t.time_ms for t in ticks]
    assert times[:8] == [4, 8, 12, 16, 20, 24, 25, 28]  # two ticks for the two pieces


def test_inc_move_returns_none_when_nothing_is_queued_and_zero_for_idle_groups(
    hc10: GroupAxes,
) -> None:
    a, b = GroupInterpolator(hc10), GroupInterpolator(hc10)
    assert inc_move([a, b]) is None
    start = still(0.0, (0.0,) * 6)
    a.start(start, to_pulses(start.pos, hc10))
    a.tool = 5
    a.set_pending(still(0.0085, (0.01,) * 6))
    a.fill(True)
    out = inc_move([a, b])
    assert out is not None
    assert out[0].tool == 5
    assert out[0].time_ms == 4
    assert out[1].pulses == (0,) * 8
    assert out[1].tool == 0


def test_a_tool_change_is_latched_per_segment_and_stops_the_merge(hc10: GroupAxes) -> None:
    g = GroupInterpolator(hc10)
    pts = [still(0.0, (0.0,) * 6), still(0.0255, (0.01,) * 6), still(0.0505, (0.02,) * 6)]
    g.start(pts[0], to_pulses(pts[0].pos, hc10))
    g.set_pending(pts[1])
    g.fill(True)
    g.tool = 3  # SELECT_TOOL between the segments
    g.set_pending(pts[2])
    g.fill(True)
    tools = [e.tool for e in g.queue]
    assert tools == [0] * 7 + [3] * 7
    ticks = []
    while (out := inc_move([g])) is not None:
        ticks.append(out[0])
    assert [t.time_ms for t in ticks][6:8] == [25, 28]  # different tools: no merge


def test_commanded_position_reaches_the_target(hc10: GroupAxes) -> None:
    start = still(0.0, (0.2, -0.3, 0.4, 0.0, 1.0, -1.0))
    end = still(0.5, (0.7, 0.3, -0.4, 1.0, 0.0, 0.5))
    g = GroupInterpolator(hc10)
    commanded = to_pulses(start.pos, hc10)
    g.start(start, commanded)
    g.set_pending(end)
    while True:
        g.fill(True)
        out = inc_move([g])
        if out is None:
            break
        commanded = add_pulses(commanded, out[0].pulses)
    assert commanded == to_pulses(end.pos, hc10)
    assert g.prev_pulses == commanded


def test_not_motion_ready_ends_the_segment_where_it_stands(hc10: GroupAxes) -> None:
    g = GroupInterpolator(hc10)
    start = still(0.0, (0.0,) * 6)
    g.start(start, to_pulses(start.pos, hc10))
    g.set_pending(still(2.0, (1.0,) * 6))
    g.fill(True)  # 200 queued, the 201st step computed and waiting for room
    blocked = list(g.queue)[-1]
    g.fill(False)
    assert not g.pending
    assert g.current.time_ms == 804  # the step after the 200th (800 ms)
    assert g.leftover_ms == 0
    assert g.prev_pulses == tuple(sum(e.pulses[k] for e in g.queue) for k in range(8))
    assert blocked.time_ms == 800
    g.clear()
    assert g.queue.count == 0
    # A later point without a new start continues from where the task stopped.
    prev = g.prev_pulses
    g.set_pending(still(1.0, (0.5,) * 6))
    g.fill(True)
    moved = [sum(e.pulses[k] for e in g.queue) for k in range(8)]
    target = to_pulses((0.5,) * 6, hc10)
    assert moved == [target[k] - prev[k] for k in range(8)]


def test_a_pending_point_is_consumed_when_not_motion_ready(hc10: GroupAxes) -> None:
    g = GroupInterpolator(hc10)
    start = still(0.0, (0.0,) * 6)
    g.start(start, to_pulses(start.pos, hc10))
    g.set_pending(still(0.1, (0.1,) * 6))
    g.fill(False)
    assert not g.pending
    assert g.queue.count == 0
    assert g.current.time_ms == 0


def test_start_resets_leftover_and_q_time(hc10: GroupAxes) -> None:
    g = GroupInterpolator(hc10)
    start = still(0.0, (0.0,) * 6)
    g.start(start, to_pulses(start.pos, hc10))
    g.set_pending(still(0.0255, (0.01,) * 6))
    g.fill(True)
    assert g.leftover_ms == 3
    again = still(0.7, (0.01,) * 6)
    g.start(again, to_pulses(again.pos, hc10))
    assert g.leftover_ms == 0
    assert g.q_time == 699  # 0.7 s as float32, truncated
    assert g.queue.count == 7  # the queue is left alone
