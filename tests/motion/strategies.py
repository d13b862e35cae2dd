"""Hypothesis strategies for random trajectories."""

from __future__ import annotations

from hypothesis import strategies as st

from pymotoros.motion import TrajPoint

# Segment lengths: whole ms (often not a multiple of 4), arbitrary fractions of a
# second, and now and then a point that is not after the one before (dropped).
_durations = st.one_of(
    st.integers(1, 150).map(lambda k: k / 1000),
    st.floats(0.0002, 0.15, allow_nan=False),
    st.sampled_from([0.025, 0.004, 0.001, 0.0, -0.003]),
)


@st.composite
def trajectories(
    draw: st.DrawFn,
    n_axes: int = 6,
    max_points: int = 5,
    max_speed: float = 2.2,
    durations: st.SearchStrategy[float] = _durations,
) -> list[TrajPoint]:
    """A start point and up to ``max_points - 1`` more, velocities within ``max_speed``."""
    count = draw(st.integers(2, max_points))
    time = draw(st.one_of(st.just(0.0), st.floats(-0.05, 2.0, allow_nan=False)))
    joint = st.floats(-3.1, 3.1, allow_nan=False)
    speed = st.floats(-max_speed, max_speed, allow_nan=False)
    points = []
    for i in range(count):
        if i:
            time += draw(durations)
        pos = tuple(draw(joint) for _ in range(n_axes))
        vel = tuple(draw(speed) for _ in range(n_axes))
        points.append(TrajPoint(time, pos, vel))
    return points
