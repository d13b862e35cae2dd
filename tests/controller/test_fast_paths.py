"""The streaming route gives the reference routes' answers and increments, bit for bit.

At dense point spacing the controller answers a streamed point without a Process
(:meth:`TrajectoryPoints.trajectory_point`) and computes a lone small segment in plain
Python (:meth:`GroupInterpolator._compute_small`, fused kernel first). The plainer
routes they replaced are oracles in ``tests/oracles``: every point through a Process
with every check run (``trajectory.py``) and every segment by the numpy kernels at once
(``interpolation.py``). Here random trajectories at 4, 8, 20 and 100 ms spacing and at
irregular times are streamed by a random client (0, 1 or 2 requests per tick, so the
queue both runs dry and fills) twice, once through the oracles and once through the
library, and every reply and every IncMove output of every tick must be equal.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from oracles.interpolation import all_at_once
from oracles.trajectory import through_a_process
from pymotoros.controller import Outcome, PointData, VirtualController
from pymotoros.controller import incmove_task as incmove_module
from pymotoros.controller.cell import default_cell
from pymotoros.controller.trajectory import TrajectoryPoints
from pymotoros.motion import GroupInterpolator, Increment
from pymotoros.protocol.constants import MotionCommand, ResultCode

from .helpers import complete, pad

CELLS = {
    "hc10 on yrc1000 (x87)": ("yrc1000", "hc10"),
    "sia20d on dx100 (x87, 7 axes, slots not in ROS order)": ("dx100", "sia20d"),
    "sda10f on fs100 (single precision)": ("fs100", "sda10f"),
}
SPACINGS_S = (0.004, 0.008, 0.02, 0.1)
"""The point spacings of issue 13 item 4; irregular times are drawn besides."""
MAX_TICKS = 4000
"""Bound of one run: 16 s of controller time, far beyond the longest drawn trajectory."""


@dataclass(frozen=True)
class Plan:
    """One drawn scenario: the points (ROS order) and the client's requests per tick."""

    times: tuple[float, ...]
    positions: tuple[tuple[float, ...], ...]
    velocities: tuple[tuple[float, ...], ...]
    requests_per_tick: tuple[int, ...]


@st.composite
def plans(draw: st.DrawFn, n_axes: int, limits: tuple[float, ...]) -> Plan:
    """A trajectory from rest at 0 rad: smooth-ish motion within the speed limits, now
    and then a velocity just over a limit (refused or let through by the truncating
    check), a point not after the previous one, or a non-finite or huge position."""
    count = draw(st.integers(2, 40))
    regular = draw(st.sampled_from((*SPACINGS_S, None)))
    times = [0.0]
    positions = [(0.0,) * n_axes]
    velocities = [(0.0,) * n_axes]
    current = positions[0]  # where the motion is (an extreme point does not move it)
    for _ in range(count - 1):
        if regular is None:
            step = draw(
                st.one_of(
                    st.integers(1, 120).map(lambda k: k / 1000),
                    st.floats(0.0002, 0.12, allow_nan=False),
                    st.sampled_from([0.004, 0.0, -0.001]),
                )
            )
            times.append(times[-1] + step)
        else:
            times.append(len(times) * regular)
        dt = max(times[-1] - times[-2], 0.0)
        vel = []
        for j in range(n_axes):
            fraction = draw(st.floats(-0.95, 0.95, allow_nan=False))
            if draw(st.integers(0, 60)) == 0:
                fraction = math.copysign(1.3, fraction)  # over the limit
            vel.append(fraction * limits[j])
        pos = tuple(
            p + 0.5 * (v0 + v1) * dt for p, v0, v1 in zip(current, velocities[-1], vel, strict=True)
        )
        current = pos
        positions.append(pos)
        velocities.append(tuple(vel))
        if draw(st.integers(0, 40)) == 0:  # an extreme but legal position on this point
            j = draw(st.integers(0, n_axes - 1))
            extreme = draw(st.sampled_from([math.nan, math.inf, -math.inf, 1e30, 3e5]))
            positions[-1] = (*pos[:j], extreme, *pos[j + 1 :])
    requests = draw(st.lists(st.sampled_from((0, 1, 1, 1, 2)), max_size=64))
    requests.append(1)  # the client sends something in every cycle of its schedule
    return Plan(tuple(times), tuple(positions), tuple(velocities), tuple(requests))


Record = list[tuple[str, object]]


@contextmanager
def general_paths(on: bool) -> Iterator[None]:
    """Controllers made inside take the reference routes (the oracles) when ``on``."""
    if not on:
        yield
        return
    with through_a_process(), all_at_once():
        yield


def stream(cell: tuple[str, str], plan: Plan, monkeypatch: pytest.MonkeyPatch) -> Record:
    """Every reply and every tick's IncMove output while the plan's client streams."""
    record: Record = []
    real_inc_move = incmove_module.inc_move

    def recording(groups: object) -> tuple[Increment, ...] | None:
        out = real_inc_move(groups)  # type: ignore[arg-type]
        record.append(("incmove", out))
        return out

    monkeypatch.setattr(incmove_module, "inc_move", recording)
    vc = VirtualController(default_cell(*cell))
    assert complete(vc, vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).ok
    n = len(plan.positions[0])
    points = [
        PointData(0, 7, t, pad(p), pad(v), pad([]))
        for t, p, v in zip(plan.times, plan.positions, plan.velocities, strict=True)
    ]
    seq = 0
    for tick in range(MAX_TICKS):
        for _ in range(plan.requests_per_tick[tick % len(plan.requests_per_tick)]):
            if seq == len(points):
                break
            outcome = complete(vc, vc.trajectory_point(seq, points[seq]))
            assert isinstance(outcome, Outcome)
            record.append(("reply", (seq, outcome)))
            if outcome.result != ResultCode.BUSY:  # anything else: the next point
                seq += 1
        if seq == len(points) and not vc.has_queued_motion():
            record.append(("command", tuple(vc.snapshot().groups[0].command_pulse[:n])))
            return record
        vc.tick()
        record.append(("queue", vc.motoros.interpolators[0].queue.count))
    raise AssertionError(f"the plan did not finish within {MAX_TICKS} ticks")


@pytest.mark.parametrize("cell", list(CELLS.values()), ids=list(CELLS))
def test_fast_paths_equal_general_paths(cell: tuple[str, str]) -> None:
    axes = VirtualController(default_cell(*cell)).motoros.interpolators[0].axes
    limits = axes.max_speed[: axes.num_axes]

    @settings(
        max_examples=25,
        deadline=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    )
    @given(plan=plans(axes.num_axes, limits))
    def check(plan: Plan) -> None:
        with pytest.MonkeyPatch.context() as mp, general_paths(True):
            reference = stream(cell, plan, mp)
        with pytest.MonkeyPatch.context() as mp, general_paths(False):
            fast = stream(cell, plan, mp)
        assert fast == reference

    check()


def test_the_switch_reaches_both_paths() -> None:
    """The comparison above is not vacuous: the oracles really are taken when switched
    on (no point answered by the library's intake, no plain-Python segment) and the
    library's route otherwise."""
    calls = {"now": 0, "small": 0}
    real_now = TrajectoryPoints._queue_point
    real_small = GroupInterpolator._compute_small

    def now(self: TrajectoryPoints, *args: object, **kwargs: object) -> Outcome:
        calls["now"] += 1
        return real_now(self, *args, **kwargs)  # type: ignore[arg-type]

    def small(self: GroupInterpolator, *args: object) -> bool:
        calls["small"] += 1
        return real_small(self, *args)  # type: ignore[arg-type]

    plan = Plan(
        tuple(k * 0.004 for k in range(30)),
        tuple((0.001 * k * k,) * 6 for k in range(30)),
        tuple((0.002 * k,) * 6 for k in range(30)),
        (1,),
    )
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(TrajectoryPoints, "_queue_point", now)
        mp.setattr(GroupInterpolator, "_compute_small", small)
        with general_paths(True):
            stream(("yrc1000", "hc10"), plan, mp)
        assert calls == {"now": 0, "small": 0}
        with general_paths(False):
            stream(("yrc1000", "hc10"), plan, mp)
        assert calls["now"] >= 29
        assert calls["small"] >= 29
