"""The check that guards every move of the client (``kinematics/sweep.py``) and the tick
sampling it runs on (``client/avoid.py:tick_positions``).

The HC10 with a ball of 0.1 m before its upper arm: with L (joint_2) at 1.0 rad the arm
is 18 mm inside it, at 0.8 rad 148 mm, from 1.1 rad on it is clear.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.client.guard import tick_positions
from pymotoros.client.planning import JointLimits, plan_joint_move
from pymotoros.kinematics.collision import CollisionWorld, Contact, world_for_cell
from pymotoros.kinematics.sweep import SweepResult, sweep
from pymotoros.models import robot_model
from pymotoros.models.cell import cell_models_from_dict

BALL = {"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75]}
TICK_S = 0.004


@pytest.fixture(scope="module")
def world() -> CollisionWorld:
    cell = cell_models_from_dict({"robot": {"model": "hc10"}, "workspace": {"obstacles": [BALL]}})
    return world_for_cell(cell)


def _along_l(world: CollisionWorld, a: float, b: float, ticks: int = 200) -> object:
    """The sweep of a straight move of L from ``a`` to ``b`` rad, the rest at zero."""
    positions = np.zeros((ticks, 6))
    positions[:, 1] = np.linspace(a, b, ticks)
    return sweep(world, np.arange(ticks) * TICK_S, positions, world.joint_counts)


def test_a_move_out_of_the_ball_recedes_and_blocks_nothing(world: CollisionWorld) -> None:
    found = _along_l(world, 1.0, 1.3)
    assert found.starts_in_contact
    assert found.start_clearance_m == pytest.approx(-0.0184, abs=1e-3)
    assert found.receding
    assert found.blocking == []
    assert {(c.link, c.at_start) for c in found.contacts} == {
        ("link_2_l", True),
        ("link_3_u", True),
    }


def test_a_move_through_the_ball_does_not_recede(world: CollisionWorld) -> None:
    found = _along_l(world, 1.0, 0.4)
    assert found.starts_in_contact
    assert not found.receding
    assert found.deepest_m < -0.14  # it passes the ball's middle
    assert found.blocking == found.contacts


def test_a_move_out_and_back_in_does_not_recede(world: CollisionWorld) -> None:
    positions = np.zeros((300, 6))
    positions[:, 1] = np.concatenate([np.linspace(1.0, 1.3, 150), np.linspace(1.3, 0.95, 150)])
    found = sweep(world, np.arange(300) * TICK_S, positions, world.joint_counts)
    assert not found.receding
    assert found.blocking  # touching again once clear


def test_a_clear_move_into_the_ball_reports_time_link_and_depth(world: CollisionWorld) -> None:
    found = _along_l(world, 0.0, 1.0, ticks=251)
    assert not found.starts_in_contact
    hit = found.blocking[0]
    assert [c.link for c in found.blocking] == ["link_2_l", "link_3_u"]
    assert hit.obstacle == "ball"
    assert hit.depth_mm > 147.0  # deepest near L = 0.8
    # the contact starts where L passes 0.49 rad (7.8 mm deep at 0.5): tick 122 of 250
    assert hit.time_s == pytest.approx(0.488, abs=TICK_S)
    assert hit.text().startswith(f"collision at {hit.time_s:.3f} s: R1 link_2_l touches obstacle")


@settings(max_examples=25, deadline=None)
@given(
    goal=st.lists(st.floats(0.0, 1.5), min_size=6, max_size=6),
    scale=st.floats(0.1, 1.0),
)
def test_tick_positions_are_motoros_cubic_at_each_tick(goal: list[float], scale: float) -> None:
    limits = JointLimits.from_group(robot_model("hc10").groups[0])
    plan = plan_joint_move([0.0] * 6, goal, limits, velocity_scaling=scale)
    times, positions = tick_positions(plan, TICK_S)
    assert times[0] == 0.0
    assert times[-1] == pytest.approx(plan.duration)
    assert np.all(np.diff(times) <= TICK_S + 1e-12)
    assert len(times) == math.ceil(plan.duration / TICK_S) + 1
    for k in range(0, len(times), max(1, len(times) // 17)):
        assert positions[k] == pytest.approx(plan.position_at(float(times[k])), abs=1e-9)
    assert positions[-1] == pytest.approx(goal, abs=1e-9)


def test_the_guard_reads_a_trajectory_in_its_groups_order() -> None:
    """``execute(trajectory, groups=(1, 0))``: the trajectory's first joints are R2's."""
    from pymotoros import PathBlockedError
    from pymotoros.client import RobotClient

    cell = cell_models_from_dict(
        {
            "controller": {"model": "dx100"},
            "groups": [{"robot": "hc10"}, {"robot": "hc10"}],
            "workspace": {
                "bases": {"R2": {"xyz": [0.0, 1.5, 0.0]}},
                "obstacles": [{**BALL, "frame": "R2"}],  # before R2's upper arm only
            },
        }
    )
    client = RobotClient(cell=cell)  # not connected: the groups stand at their home
    into = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    plan = client.plan([0.0] * 12, into + [0.0] * 6, groups=(1, 0))
    with pytest.raises(PathBlockedError, match="R2 link_2_l touches obstacle 'ball'"):
        client.guard(plan, (1, 0))
    assert client.guard(plan, (0, 1)) is None  # the same joints move R1: no ball there


class _Scripted:
    """A collision model that reports, at tick k (the first joint holds k), the signed
    distance (mm) of each (link, obstacle) given for that tick: two contacts at once."""

    def __init__(self, ticks: list[dict[tuple[str, str], float]]) -> None:
        self.ticks = ticks

    def probe(self, qs: list[np.ndarray]) -> tuple[float, list[Contact]]:
        here = self.ticks[round(float(qs[0][0]))]
        contacts = [Contact(o, link, "R1", mm / 1000.0) for (link, o), mm in here.items()]
        return min((c.distance_m for c in contacts), default=0.05), contacts

    def self_distances(self, qs: list[np.ndarray]) -> list[Contact]:
        return []

    def joint_reach(self, group_index: int) -> list[float]:
        return [1.0]

    def lever_arms(self, group_index: int) -> list[float]:
        return [1.0]


def _scripted(ticks: list[dict[tuple[str, str], float]]) -> SweepResult:
    k = np.arange(len(ticks), dtype=float)
    return sweep(_Scripted(ticks), k * TICK_S, k[:, None], [1])


def _two_contacts(tool: list[float], link_5: list[float]) -> list[dict[tuple[str, str], float]]:
    return [
        {("tool", "fixture"): a, ("link_5", "table"): b} for a, b in zip(tool, link_5, strict=True)
    ]


def test_each_contact_is_judged_on_its_own_in_a_back_out() -> None:
    """The tool 3 -> 2.5 mm out of the fixture while link_5 goes 1.0 -> 2.4 mm into the
    table: the smallest distance grows (-3 -> -2.5 mm) but link_5 goes deeper: refused."""
    found = _scripted(_two_contacts([-3.0, -2.8, -2.6, -2.5], [-1.0, -1.6, -2.0, -2.4]))
    assert found.starts_in_contact
    assert not found.receding
    assert found.worse is not None
    assert (found.worse.link, found.worse.obstacle) == ("link_5", "table")
    assert found.worse.start_mm == pytest.approx(1.0)
    assert found.worse.depth_mm == pytest.approx(1.6)
    assert {c.link for c in found.blocking} == {"tool", "link_5"}
    both_out = _scripted(_two_contacts([-3.0, -2.8, -2.6, -2.5], [-1.0, -0.8, -0.5, -0.2]))
    assert both_out.receding
    assert both_out.blocking == []


def test_a_new_contact_during_a_back_out_is_refused() -> None:
    """The tool leaves the fixture while link_5 touches the table for the first time."""
    ticks = [
        {("tool", "fixture"): -3.0},
        {("tool", "fixture"): -2.0},
        {("tool", "fixture"): -1.0, ("link_5", "table"): -0.5},
    ]
    found = _scripted(ticks)
    assert not found.receding
    assert found.worse is not None
    assert (found.worse.link, found.worse.start_mm) == ("link_5", None)
    assert [c.link for c in found.blocking if not c.at_start] == ["link_5"]
