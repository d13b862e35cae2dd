"""Nothing a client sends sets the work of a tick (issue 13, item 1).

A legal JOINT_TRAJ_PT_FULL may be up to 14,400 s after the previous point (§3.4): 3.6
million steps at 4 ms. The interpolator must plan and compute them as the 200-entry
queue takes them, not all at once; before this, one such point held the loop for
about 17 s and grew the process by about 1 GB. The tests count the entries computed
per batch (deterministic), rather than timing ticks.
"""

from __future__ import annotations

import pytest

import pymotoros.motion.interpolator as interpolator
from pymotoros.motion.constants import QUEUE_SIZE
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, current_pos, point, send, start_at_current
from .states import ready

LONGEST_LEGAL_S = 14399.0
"""Just under MotoROS's 14,400 s limit on a point's time (§3.4 step 3)."""

BOUND = QUEUE_SIZE + interpolator.PIECE_ENTRIES
"""Entries one batch may compute: what the queue holds plus the piece being planned."""


@pytest.fixture
def batch_sizes(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Record the number of entries of every vectorised computation the interpolator
    makes: batches of queued segments and the oldest queued segment alone."""
    sizes: list[int] = []
    real = interpolator.queued_targets
    real_one = interpolator.segment_targets

    def counting(*args: object, **kwargs: object) -> object:
        times, targets = real(*args, **kwargs)  # type: ignore[arg-type]
        sizes.append(len(times))
        return times, targets

    def counting_one(*args: object, **kwargs: object) -> object:
        targets = real_one(*args, **kwargs)  # type: ignore[arg-type]
        sizes.append(len(targets))
        return targets

    monkeypatch.setattr(interpolator, "queued_targets", counting)
    monkeypatch.setattr(interpolator, "segment_targets", counting_one)
    return sizes


def test_a_point_14399_s_away_is_computed_piece_by_piece(batch_sizes: list[int]) -> None:
    vc = ready()
    assert start_at_current(vc).ok
    target = current_pos(vc)
    target[0] += 0.5
    outcome = send(vc, 1, point(0, LONGEST_LEGAL_S, target))
    assert outcome.result == R.SUCCESS, outcome
    vc.run_ticks(3 * QUEUE_SIZE)  # several pieces planned, computed and consumed
    assert batch_sizes, "the interpolator computed nothing"
    assert max(batch_sizes) <= BOUND, batch_sizes
    assert sum(batch_sizes) <= 3 * QUEUE_SIZE + 2 * BOUND
    # The robot is on its way: the queue stays full and the next point is BUSY.
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == QUEUE_SIZE
    busy = vc.trajectory_point(2, point(0, LONGEST_LEGAL_S, target))
    assert vc.wait_for(busy).result == R.BUSY


def test_stopping_a_long_segment_computes_one_step(batch_sizes: list[int]) -> None:
    """STOP_MOTION in the middle of the long segment: the state where it stopped comes from
    the blocked step alone, and a new trajectory can start from there."""
    vc = ready()
    assert start_at_current(vc).ok
    target = current_pos(vc)
    target[1] += 0.25
    assert send(vc, 1, point(0, LONGEST_LEGAL_S, target)).ok
    vc.run_ticks(QUEUE_SIZE + 17)
    assert command(vc, CMD.STOP_MOTION).ok
    assert max(batch_sizes) <= BOUND
    vc.run_ticks(QUEUE_SIZE)
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == 0
    assert start_at_current(vc).ok


def test_a_hold_in_a_long_segment_ends_it_where_it_stands(batch_sizes: list[int]) -> None:
    """HOLD makes the controller not motion-ready: the segment is cut at the blocked step
    (§5.4), found without computing the millions of steps after it."""
    vc = ready()
    assert start_at_current(vc).ok
    target = current_pos(vc)
    target[2] -= 0.25
    assert send(vc, 1, point(0, LONGEST_LEGAL_S, target)).ok
    vc.run_ticks(2 * QUEUE_SIZE + 5)
    vc.set_hold(True)
    vc.run_ticks(2 * QUEUE_SIZE)
    assert max(batch_sizes) <= BOUND
    vc.set_hold(False)
    assert command(vc, CMD.CHECK_QUEUE_CNT).subcode == 0
