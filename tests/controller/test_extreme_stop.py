"""STOP_MOTION in the middle of a segment to a non-finite point (found by the robustness
suite, issue 13): the blocked step used to be computed by the float64 shortcut, which
crashed on NaN and infinities (``int(frexp(nan)...)``) and took the interpolation loop,
and with it the whole simulator, down. Deterministic, in virtual time."""

from __future__ import annotations

import math

import pytest

from pymotoros.controller import VirtualController

from .helpers import CMD, command, complete, enter_traj_mode, point, start_at_current

NON_FINITE = [math.nan, math.inf, -math.inf]


@pytest.mark.parametrize("value", NON_FINITE, ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("axis", range(6))
@pytest.mark.parametrize("ticks_before_stop", [0, 1, 2, 5])
def test_stop_in_a_segment_to_a_non_finite_point(
    value: float, axis: int, ticks_before_stop: int
) -> None:
    vc = VirtualController()
    enter_traj_mode(vc)
    start_at_current(vc)
    target = [0.0] * 6
    target[axis] = value
    complete(vc, vc.trajectory_point(1, point(0, 1.0, target)))
    for _ in range(ticks_before_stop):
        vc.tick()
    assert command(vc, CMD.STOP_MOTION).ok
    for _ in range(3):
        vc.tick()
    assert all(math.isfinite(x) for x in vc.snapshot().groups[0].command_rad)
