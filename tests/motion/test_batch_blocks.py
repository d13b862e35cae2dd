"""How ``batch.batch_increments`` splits the work does not change a bit of the result.

Short segments are computed step rank by step rank (with a strided view of the output
when the points are evenly spaced), long ones with a gather per step; blocks may run on
worker threads; ``on_block`` hands out the leading entries as they become final. Every
split is checked against the literal per-segment task of ``test_batch.per_segment``.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.motion import GroupAxes, TrajPoint, batch, interpolate, offline

from .helpers import axes_for
from .strategies import trajectories
from .test_batch import CELLS, DENSE, fit, per_segment

I64 = np.ndarray


@st.composite
def evenly_spaced(draw: st.DrawFn) -> list[TrajPoint]:
    """Points at one spacing (the strided path), now and then a longer segment."""
    spacing = draw(st.sampled_from([0.004, 0.008, 0.02, 0.0205, 0.05]))
    points = draw(trajectories(max_points=40, durations=st.just(spacing)))
    if draw(st.booleans()):
        last = points[-1]
        points.append(TrajPoint(last.time + draw(st.sampled_from([0.2, 0.5])), last.pos, last.vel))
    return points


SPLITS = st.tuples(
    st.sampled_from([0, 1, 2, 32]),  # SHORT_STEPS: 0 sends every segment to the gather
    st.sampled_from([1, 3, 1024]),  # SEGMENT_CHUNK
    st.sampled_from([1, 5, 2048]),  # CHUNK
    st.sampled_from([1, 2]),  # worker threads
)


def split_run(
    points: list[TrajPoint], axes: GroupAxes, split: tuple[int, int, int, int]
) -> tuple[list[tuple[int, list[int]]], list[tuple[int, I64, I64]]]:
    """The engine's entries with the given split, and what ``on_block`` saw (copies)."""
    short, segments, chunk, workers = split
    seen: list[tuple[int, I64, I64]] = []

    def on_block(time_ms: I64, increments: I64, done: int) -> None:
        seen.append((done, time_ms[:done].copy(), increments[:done].copy()))

    real = batch.batch_increments

    def with_workers(*args: object, **kwargs: object) -> tuple[I64, I64]:
        return real(*args, workers=workers, **kwargs)  # type: ignore[arg-type]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(batch, "SHORT_STEPS", short)
        mp.setattr(batch, "SEGMENT_CHUNK", segments)
        mp.setattr(batch, "CHUNK", chunk)
        mp.setattr(offline, "batch_increments", with_workers)
        times, incs = interpolate(points, axes, validate=False)
        offline.interpolate_arrays(
            np.array([p.time for p in points]),
            np.array([p.pos for p in points]),
            np.array([p.vel for p in points]),
            axes,
            validate=False,
            on_block=on_block,
        )
    entries = list(zip(times.tolist(), incs.tolist(), strict=True))
    return entries, seen


@settings(max_examples=80, deadline=None)
@given(
    st.one_of(
        evenly_spaced(),
        trajectories(max_points=12, durations=DENSE),
        trajectories(max_points=8),
    ),
    st.sampled_from(CELLS),
    SPLITS,
)
def test_every_split_gives_the_per_segment_entries(
    points: list[TrajPoint], cell: tuple[str, str], split: tuple[int, int, int, int]
) -> None:
    axes = axes_for(*cell)
    points = fit(points, axes)
    entries, seen = split_run(points, axes, split)
    assert entries == per_segment(points, axes)
    # on_block: growing prefixes, each already final when handed out, the last whole.
    dones = [done for done, _, _ in seen]
    assert dones == sorted(dones)
    if entries:
        assert dones[-1] == len(entries)
    for done, time_ms, increments in seen:
        assert list(zip(time_ms.tolist(), increments.tolist(), strict=True)) == entries[:done]
