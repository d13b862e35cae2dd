"""Several groups streaming with the queue's oldest segment computed alone, or not.

The interpolator computes each group's oldest queued segment alone when IncMove reaches
it (``GroupInterpolator._compute_front``); the reference route
(``tests/oracles/interpolation.py``) computes every queued segment of a group at once.
Here every group of multi-group cells streams random points through
JOINT_TRAJ_PT_FULL_EX, with segments long enough to take the front path and short
ones that do not, and every tick's IncMove output and the final command positions must
be the same both ways (``tests/motion/test_front_path.py`` compares the kernels).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from contextlib import nullcontext

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from oracles.interpolation import all_at_once
from pymotoros.controller import VirtualController, default_cell
from pymotoros.controller import incmove_task as incmove_module
from pymotoros.motion import Increment, interpolator
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, complete, point

MAX_TICKS = 6000
"""Bound of one run: 24 s of controller time, beyond the longest drawn trajectory."""
CELLS = {
    "sda10f on fs100 (4 groups, single precision)": ("fs100", "sda10f"),
    "sda10f on dx200 (4 groups, x87)": ("dx200", "sda10f"),
}


def stream(
    cell: tuple[str, str], gaps: Sequence[float], shape: Sequence[float], *, front: bool
) -> tuple[list[tuple[Increment, ...] | None], list[tuple[int, ...]], int]:
    """(IncMove output per tick, final command pulses per group, segments computed
    alone) with every group streaming the same timing and its own positions."""
    record: list[tuple[Increment, ...] | None] = []
    alone = [0]
    real_inc_move = incmove_module.inc_move
    real_one = interpolator.segment_targets

    def recording(groups: object) -> tuple[Increment, ...] | None:
        out = real_inc_move(groups)  # type: ignore[arg-type]
        record.append(out)
        return out

    def counting(*args: object, **kwargs: object) -> object:
        alone[0] += 1
        return real_one(*args, **kwargs)  # type: ignore[arg-type]

    with pytest.MonkeyPatch.context() as mp, nullcontext() if front else all_at_once():
        mp.setattr(incmove_module, "inc_move", recording)
        mp.setattr(interpolator, "segment_targets", counting)
        vc = VirtualController(default_cell(*cell))
        assert command(vc, CMD.START_TRAJ_MODE).ok
        groups = vc.cell.groups
        start = [list(g.command_rad) for g in vc.snapshot().groups]
        times = [0.0]
        for gap in gaps:
            times.append(times[-1] + gap)
        for seq, (t, s) in enumerate(zip(times, (0.0, *shape), strict=False)):
            pts = [
                point(
                    g,
                    t,
                    [
                        p + 0.05 * (g + 1) * math.sin(s + j) * (seq > 0)
                        for j, p in enumerate(start[g][: len(m.axes)])
                    ],
                )
                for g, m in enumerate(groups)
            ]
            for _ in range(MAX_TICKS):
                outcome = complete(vc, vc.trajectory_point_ex(seq, pts))
                if outcome.result != R.BUSY:
                    break
                vc.tick()
            assert outcome.ok, (seq, outcome)
        interps = vc.motoros.interpolators
        for _ in range(MAX_TICKS):
            if not vc.has_queued_motion() and not any(i.pending for i in interps):
                break
            vc.tick()
        else:
            raise AssertionError("the trajectory did not drain")
        vc.tick()  # the last entries reach the servos
        commands = [tuple(g.command_pulse) for g in vc.snapshot().groups]
    return record, commands, alone[0]


@pytest.mark.parametrize("cell", list(CELLS.values()), ids=list(CELLS))
def test_groups_stream_the_same_with_and_without_the_front_path(cell: tuple[str, str]) -> None:
    alone: list[int] = []

    @settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(
        gaps=st.lists(
            st.one_of(st.integers(80, 300), st.integers(4, 79)).map(lambda k: k / 1000),
            min_size=1,
            max_size=6,
        ),
        shape=st.lists(st.floats(-3.0, 3.0), min_size=7, max_size=7),
    )
    @example(gaps=[0.1, 0.1, 0.1], shape=[0.5] * 7)  # every segment alone
    def check(gaps: list[float], shape: list[float]) -> None:
        front = stream(cell, gaps, shape, front=True)
        together = stream(cell, gaps, shape, front=False)
        assert front[:2] == together[:2]
        assert together[2] == 0
        alone.append(front[2])

    check()
    assert max(alone) > 0, "no segment was computed alone"
