"""The step grid and the leftover carried across segments (§5.4)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.motion import GroupAxes, GroupInterpolator, interpolate, to_pulses
from pymotoros.motion.offline import _plan_loop, _plan_vectorised
from pymotoros.motion.segment import Grid, plan_grid

from .helpers import still


def test_25ms_segment_at_4ms_is_six_steps_and_a_1ms_step() -> None:
    grid = plan_grid(0, 25, 0, 4)
    assert grid == Grid(first_ms=4, full_steps=6, leftover_ms=3)
    # the next segment starts with the 3 ms leftover, then whole periods
    assert plan_grid(25, 50, 3, 4) == Grid(first_ms=28, full_steps=6, leftover_ms=2)


@pytest.mark.parametrize(
    ("start", "end", "leftover", "expected"),
    [
        (0, 8, 0, Grid(4, 1, 0)),  # lands exactly on the grid
        (0, 3, 0, Grid(4, 0, 1)),  # shorter than a period: one step, overshoot 1
        (0, 5, 3, Grid(3, 1, 2)),  # leftover step 3, then 7 > 5
        (0, 2, 3, Grid(3, 0, 1)),  # the leftover step itself overshoots
        (0, 3, 3, Grid(3, 0, 3)),  # quirk: lands exactly, the leftover stays 3
        (10, 11, 0, Grid(14, 0, 3)),
    ],
)
def test_grid_cases(start: int, end: int, leftover: int, expected: Grid) -> None:
    assert plan_grid(start, end, leftover, 4) == expected


def test_entry_times_of_two_25ms_segments(hc10: GroupAxes) -> None:
    points = [still(0.0, (0.0,) * 6), still(0.025, (0.01,) * 6), still(0.05, (0.02,) * 6)]
    times, _ = interpolate(points, hc10)
    assert times.tolist() == [4, 8, 12, 16, 20, 24, 25, 28, 32, 36, 40, 44, 48, 50]


def test_equal_quirk_keeps_the_leftover_for_the_following_segment(hc10: GroupAxes) -> None:
    # 25 ms leaves 3 ms; a 3 ms segment lands exactly on its end with that step, so the
    # leftover stays 3 ms and the third segment starts with a 3 ms step again.
    # Times sit half a ms past the grid so that float32 cannot pull them under
    # (0.040 s is 0.03999999911 as float32 and would become 39 ms).
    points = [
        still(0.0, (0.0,) * 6),
        still(0.0255, (0.01,) * 6),
        still(0.0285, (0.011,) * 6),
        still(0.0405, (0.012,) * 6),
    ]
    g = GroupInterpolator(hc10)
    g.start(points[0], to_pulses(points[0].pos, hc10))
    times = []
    for p in points[1:]:
        g.set_pending(p)
        g.fill(True)
        assert not g.pending
        times += [g.queue.pop().time_ms for _ in range(g.queue.count)]
    assert times == [4, 8, 12, 16, 20, 24, 25, 28, 31, 35, 39, 40]
    assert g.leftover_ms == 3


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.integers(-20, 60), min_size=1, max_size=30).map(
        lambda steps: [sum(steps[: i + 1]) for i in range(len(steps))]
    ),
    st.sampled_from([4, 8, 1]),
)
def test_vectorised_grid_plan_equals_the_loop(ms: list[int], period: int) -> None:
    """The phase argument of the vectorised planner, against the literal loop."""
    looped = _plan_loop(ms, period)
    fast = _plan_vectorised(np.array(ms, dtype=np.int64), period)
    if fast is None:  # the quirk occurred: the loop decides
        return
    for a, b in zip(fast, looped, strict=True):
        assert list(np.asarray(a).tolist()) == list(b)


def test_vectorised_plan_gives_up_on_the_quirk() -> None:
    # 0 → 25 ms leaves 3 ms; 25 → 28 ms is the 3 ms step landing exactly: quirk.
    assert _plan_vectorised(np.array([0, 25, 28, 40], dtype=np.int64), 4) is None
    assert _plan_loop([0, 25, 28, 40], 4)[2] == [4, 28, 31]
