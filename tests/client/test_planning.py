"""Motion generation: limits respected, near time-optimal, MotoROS-acceptable points."""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.client.planning import (
    MIN_SAMPLE_PERIOD_S,
    JointLimits,
    PlanningError,
    TrajectoryPoint,
    motoros_speed_limit,
    plan_joint_move,
)
from pymotoros.client.preflight import speed_deviations
from pymotoros.models import ROBOTS, FloatMode, GroupModel, controller_model, robot_model
from pymotoros.models.rules import GroupRules

YRC1000 = controller_model("yrc1000")

HC10 = robot_model("hc10").groups[0]
LIMITS = JointLimits.from_group(HC10)
EPS = 1e-9


def _positions(limits: JointLimits) -> st.SearchStrategy[tuple[float, ...]]:
    return st.tuples(
        *(
            st.floats(lo, hi, allow_nan=False, allow_infinity=False)
            for lo, hi in zip(limits.lower, limits.upper, strict=True)
        )
    )


scaling = st.floats(0.05, 1.0)


GROUPS = [g for model in ROBOTS.values() for g in model.groups]


@st.composite
def moves(draw: st.DrawFn) -> tuple[GroupModel, tuple[float, ...], tuple[float, ...]]:
    group = draw(st.sampled_from(GROUPS))
    limits = JointLimits.from_group(group)
    return group, draw(_positions(limits)), draw(_positions(limits))


@settings(max_examples=100, deadline=None)
@given(
    move=moves(),
    vs=scaling,
    acc=scaling,
    period=st.sampled_from([0.004, 0.01, 0.02, 0.05]),
)
def test_moves_respect_limits_and_are_near_optimal(
    move: tuple[GroupModel, tuple[float, ...], tuple[float, ...]],
    vs: float,
    acc: float,
    period: float,
) -> None:
    group, start, goal = move
    limits = JointLimits.from_group(group)
    traj = plan_joint_move(
        start, goal, limits, velocity_scaling=vs, acceleration_scaling=acc, sample_period=period
    )
    pts = traj.points
    assert pts[0].time == 0.0
    assert pts[0].positions == pytest.approx(start)
    assert pts[-1].positions == pytest.approx(goal, abs=1e-9)
    assert all(v == 0.0 for v in pts[-1].velocities)
    assert traj.duration <= 1.1 * traj.optimal_duration + EPS
    for a, b in itertools.pairwise(pts):
        assert b.time - a.time >= MIN_SAMPLE_PERIOD_S - EPS
        assert b.time - a.time <= max(period, 2 * MIN_SAMPLE_PERIOD_S) + EPS
    for p in pts:
        assert speed_deviations(p, [group], YRC1000) == []
        for i, axis in enumerate(group.axes):
            lo, hi = min(start[i], goal[i]), max(start[i], goal[i])
            assert lo - 1e-9 <= p.positions[i] <= hi + 1e-9
            assert axis.lower - EPS <= p.positions[i] <= axis.upper + EPS
            assert abs(p.velocities[i]) <= limits.max_velocity[i] * vs * (1 + 1e-9)
            assert abs(p.velocities[i]) <= axis.max_velocity
            if p.accelerations:
                assert abs(p.accelerations[i]) <= axis.max_acceleration * acc * (1 + 1e-6)


@settings(max_examples=20, deadline=None)
@given(goal=_positions(LIMITS))
def test_duration_grows_as_speed_scaling_falls(goal: tuple[float, ...]) -> None:
    start = HC10.home
    fast = plan_joint_move(start, goal, LIMITS)
    slow = plan_joint_move(start, goal, LIMITS, velocity_scaling=0.25, acceleration_scaling=0.25)
    assert slow.duration >= fast.duration - EPS


def test_every_model_has_limits_motoros_accepts() -> None:
    for model in ROBOTS.values():
        for group in model.groups:
            limits = JointLimits.from_group(group)
            for axis, v in zip(group.axes, limits.max_velocity, strict=True):
                assert 0 < v <= axis.max_velocity
            point = TrajectoryPoint(0.1, group.home, limits.max_velocity)
            assert speed_deviations(point, [group], YRC1000) == []


def test_same_start_and_goal_is_one_point() -> None:
    traj = plan_joint_move(HC10.home, HC10.home, LIMITS)
    assert len(traj.points) == 1
    assert traj.duration == 0.0


def test_goal_outside_limits_is_refused() -> None:
    goal = list(HC10.home)
    goal[2] = math.radians(-10)
    with pytest.raises(PlanningError, match="joint_3_u") as refused:
        plan_joint_move(HC10.home, goal, LIMITS)
    # every number with its unit (issue 29): the goal and the limits in rad and deg
    lo, hi = LIMITS.lower[2], LIMITS.upper[2]
    assert str(refused.value) == (
        f"goal -0.174533 rad (-10.000 deg) for joint_3_u is outside its limits "
        f"[{lo:.6f}, {hi:.6f}] rad ([{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg); "
        "give a goal within them"
    )


def test_a_linear_axis_goal_outside_its_limits_is_in_metres() -> None:
    track = JointLimits(("base_x",), (0.0,), (2.0,), (1.0,), (2.0,), (20.0,), linear=(True,))
    with pytest.raises(PlanningError) as refused:
        plan_joint_move((0.5,), (2.5,), track)
    assert str(refused.value) == (
        "goal 2.500000 m for base_x is outside its limits [0.000000, 2.000000] m; "
        "give a goal within them"
    )


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.5, math.nan])
def test_scaling_must_be_a_fraction(bad: float) -> None:
    with pytest.raises(PlanningError, match="velocity_scaling"):
        plan_joint_move(HC10.home, [0.1] * 6, LIMITS, velocity_scaling=bad)


def test_wrong_joint_count_names_the_joints() -> None:
    with pytest.raises(PlanningError, match="joint_1_s"):
        plan_joint_move([0.0] * 5, [0.0] * 6, LIMITS)


def test_position_at_and_progress_follow_the_plan() -> None:
    traj = plan_joint_move(HC10.home, (0.5, 0, 0, 0, -1.0, 0), LIMITS)
    assert traj.position_at(0.0) == traj.start
    assert traj.position_at(traj.duration + 1) == traj.goal
    mid = traj.position_at(traj.duration / 2)
    assert traj.progress(mid) == pytest.approx(0.5, abs=0.02)
    assert traj.time_at_progress(traj.progress(mid)) == pytest.approx(traj.duration / 2, abs=0.01)


def test_motoros_speed_check_truncates_like_the_controller() -> None:
    # S axis limit 2.2689 rad/s: trunc(|v|) > limit refuses only from 3 rad/s on
    def refused(v: float) -> bool:
        point = TrajectoryPoint(0.1, HC10.home, (v,) + (0.0,) * 5)
        return bool(speed_deviations(point, [HC10], YRC1000))

    assert not refused(2.9)
    assert refused(3.0)
    assert refused(-3.0)


@pytest.mark.parametrize("controller", ["yrc1000", "fs100"])
def test_speed_limit_is_the_controllers_float32_number(controller: str) -> None:
    ctrl = controller_model(controller)
    for model in ROBOTS.values():
        for group in model.groups:
            rules = GroupRules.from_model(group, ctrl)
            for i, axis in enumerate(group.axes):
                limit = motoros_speed_limit(axis, 4, ctrl.float_mode)
                assert limit == rules.max_speed[i]
    assert motoros_speed_limit(HC10.axes[0], 4) == motoros_speed_limit(
        HC10.axes[0], 4, FloatMode.X87_EXTENDED
    )


def test_several_groups_are_planned_as_one_synchronised_move() -> None:
    groups = robot_model("sda10f").groups
    limits = JointLimits.concat([JointLimits.from_group(g) for g in groups])
    start = tuple(v for g in groups for v in g.home)
    goal = tuple(min(0.5, hi) for hi in limits.upper)
    traj = plan_joint_move(start, goal, limits)
    assert limits.dof == sum(g.num_axes for g in groups)
    assert traj.goal == goal
    for p in traj.points:
        assert all(
            abs(v) <= vmax * (1 + 1e-9)
            for v, vmax in zip(p.velocities, limits.max_velocity, strict=True)
        )
    # Phase synchronisation: every joint is the same fraction of the way at every point.
    for p in traj.points[1:-1]:
        fractions = [
            (x - s) / (g - s) for x, s, g in zip(p.positions, start, goal, strict=True) if g != s
        ]
        assert max(fractions) - min(fractions) < 1e-6
