"""``check_trajectory`` predicts the twin exactly: its refusals, its increments, its duration."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pymotoros.controller.cell import load_cell
from pymotoros.models import ControllerModel, RobotModel, controller_model, robot_model
from pymotoros.models.cell import load_cell_models
from pymotoros.models.rules import to_pulses
from pymotoros.motion import GroupAxes
from pymotoros.protocol.constants import InvalidSubcode
from pymotoros.trajectory import (
    CheckReport,
    Trajectory,
    check_against_cell,
    check_trajectory,
    plan_waypoints,
)
from pymotoros.trajectory.check import (
    EXIT_OK,
    EXIT_REFUSED,
    EXIT_WARNINGS,
    fsu_clip,
    fsu_execution,
)
from pymotoros.trajectory.planning import MIN_WAYPOINT_STEP, WaypointPlanningError

from .twin_run import TwinOutcome, run_on_twin, twin_start

HC10 = robot_model("hc10")
YRC = controller_model("yrc1000")
NAMES = HC10.groups[0].joint_names
AXES = GroupAxes.from_model(HC10.groups[0], YRC)
START = asyncio.run(twin_start())


def _traj(times: list[float], pos: list[list[float]], vel: list[list[float]]) -> Trajectory:
    return Trajectory(NAMES, np.array(times), np.array(pos), np.array(vel))


def _assert_same_as_twin(traj: Trajectory) -> None:
    report = check_trajectory(traj, HC10, YRC)
    outcome = asyncio.run(run_on_twin(traj))
    if report.refusal is not None:
        assert outcome.refused is not None, "check predicted a refusal the twin did not give"
        assert outcome.refused.subcode == report.refusal.subcode
        assert outcome.refused.point == report.refusal.point
        return
    assert outcome.refused is None, outcome.refused
    _assert_same_motion(report, outcome, HC10, YRC)


def _assert_same_motion(
    report: CheckReport, outcome: TwinOutcome, robot: RobotModel, controller: ControllerModel
) -> None:
    """Tick for tick over the whole motion (first to last executed queue entry, still
    ones included), per group: the increments, their count and the duration."""
    assert outcome.paused_ticks == 0, "the twin's queue ran dry: the client fed it too slowly"
    assert report.increments == outcome.executed_ticks > 0
    assert report.duration_s == pytest.approx(outcome.duration_s, abs=1e-9)
    for gi, group in enumerate(robot.groups):
        axes = GroupAxes.from_model(group, controller)
        _, predicted = report.per_group[group.name]
        executed = outcome.executed_increments(gi, axes.axis_slots)
        # a group with fewer ticks than the longest stands still for the rest
        assert len(predicted) <= len(executed)
        np.testing.assert_array_equal(executed[: len(predicted)], predicted)
        assert not executed[len(predicted) :].any()


def _still(t: float) -> list[float]:
    return [0.0] * len(NAMES)


def there_and_back() -> Trajectory:
    """A planned trajectory from START (where the twin boots) to S +0.4 rad and B -0.3
    rad, and back."""
    goal = list(START)
    goal[0] += 0.4
    goal[4] -= 0.3
    return plan_waypoints([START, goal, START], HC10, YRC)


def test_accepted_planned_trajectory_matches_the_twin_increment_for_increment() -> None:
    traj = there_and_back()
    report = check_trajectory(traj, HC10, YRC)
    assert report.exit_code == EXIT_OK, report.to_json()
    _assert_same_as_twin(traj)


def test_refused_start_position_3011() -> None:
    moved = list(START)
    moved[2] += 0.01  # far beyond 30 pulses
    goal = list(moved)
    goal[0] += 0.1
    traj = _traj([0.0, 1.0], [moved, goal], [_still(0), _still(1)])
    # without --from the robot stands at the start: accepted
    assert check_trajectory(traj, HC10, YRC).accepted
    report = check_trajectory(traj, HC10, YRC, current=START)
    assert report.exit_code == EXIT_REFUSED
    assert report.refusal is not None
    assert report.refusal.subcode == InvalidSubcode.DATA_START_POS
    assert report.refusal.point == 0
    assert report.refusal.axis == "joint_3_u"
    assert report.refusal.limit == 30
    outcome = asyncio.run(run_on_twin(traj))
    assert outcome.refused is not None
    assert outcome.refused.subcode == report.refusal.subcode == 3011
    assert outcome.refused.point == 0


def test_start_margin_is_reported() -> None:
    shifted = list(START)
    factor = AXES.pulses_per_unit[AXES.ros_to_slot[0]]
    shifted[0] += 20.5 / factor
    traj = _traj([0.0, 1.0], [shifted, shifted], [_still(0), _still(1)])
    report = check_trajectory(traj, HC10, YRC, current=START)
    assert report.accepted
    commanded = to_pulses(START, AXES)[0]
    requested = to_pulses(shifted, AXES)[0]
    assert report.start_margin_pulses == 30 - abs(requested - commanded)


def test_refused_speed_3013_matches_the_twin() -> None:
    goal = list(START)
    goal[0] += 1.0
    fast = _still(0)
    fast[0] = 3.5  # above joint_1_s's 2.27 rad/s, and trunc(3.5) = 3 > 2.27
    traj = _traj([0.0, 1.0, 2.0], [START, goal, goal], [_still(0), fast, _still(2)])
    report = check_trajectory(traj, HC10, YRC)
    assert report.refusal is not None
    assert (report.refusal.subcode, report.refusal.point, report.refusal.axis) == (
        3013,
        1,
        "joint_1_s",
    )
    assert report.refusal.value == pytest.approx(3.5)
    assert "slower" in report.refusal.remedy
    _assert_same_as_twin(traj)


def test_refused_time_3016_matches_the_twin() -> None:
    traj = _traj([0.0, 14400.0], [START, START], [_still(0), _still(1)])
    report = check_trajectory(traj, HC10, YRC)
    assert report.refusal is not None
    assert (report.refusal.subcode, report.refusal.point) == (3016, 1)
    _assert_same_as_twin(traj)


def test_overshoot_between_points_is_a_warning_and_the_twin_does_overshoot() -> None:
    # joint_3_u's lower limit is -5°: a cubic from 0 to 0 in 1 s ending at +1 rad/s dips
    # to -4/27 rad (-8.5°) at t = 2/3 s. Both points are within the limits.
    start = list(START)
    start[2] = 0.0
    vel_end = _still(1)
    vel_end[2] = 1.0
    traj = _traj([0.0, 1.0, 1.6], [start, start, start], [_still(0), vel_end, _still(2)])
    report = check_trajectory(traj, HC10, YRC)
    kinds = {w.kind for w in report.warnings}
    assert report.exit_code == EXIT_WARNINGS
    assert "position" in kinds
    position = next(w for w in report.warnings if w.kind == "position")
    assert position.axis == "joint_3_u"
    assert position.point == 1
    assert position.value == pytest.approx(-4 / 27, abs=2e-3)
    assert position.limit == pytest.approx(HC10.groups[0].axes[2].lower)
    assert tuple(start) == START  # the twin boots at zero
    _assert_same_as_twin(traj)
    outcome = asyncio.run(run_on_twin(traj))
    slot = AXES.ros_to_slot[2]
    deepest = min(c[0][slot] for c in outcome.commands) / AXES.pulses_per_unit[slot]
    assert deepest == pytest.approx(position.value, abs=1e-4)  # the twin really goes there


def test_feed_rate_problem_is_a_warning() -> None:
    goal = list(START)
    goal[0] += 0.002
    times = [0.0, 0.5, 0.502, 0.504, 1.0]
    pos = [START, START, START, goal, goal]
    traj = _traj(times, pos, [_still(0)] * 5)
    report = check_trajectory(traj, HC10, YRC)
    feed = [w for w in report.warnings if w.kind == "feed"]
    assert len(feed) == 1
    # 0.502 s is 0.50199997 in float32: MotoROS truncates it to 501 ms, 1 ms after 500
    assert (feed[0].point, feed[0].value, feed[0].limit) == (2, 1.0, 4.0)
    assert report.exit_code == EXIT_WARNINGS
    _assert_same_as_twin(traj)  # the duration the check predicts is the one the twin takes


def test_dropped_point_is_a_warning() -> None:
    traj = _traj([0.0, 0.5, 0.5, 1.0], [START] * 4, [_still(0)] * 4)
    report = check_trajectory(traj, HC10, YRC)
    assert [w.kind for w in report.warnings] == ["dropped"]
    assert report.warnings[0].point == 2


def test_acceleration_excess_needs_more_than_rounding() -> None:
    goal = list(START)
    goal[3] += 0.5
    # 0.5 rad in 0.3 s from rest to rest: peak acceleration 6·0.5/0.09 ≈ 33 rad/s² > 7.5
    traj = _traj([0.0, 0.3], [START, goal], [_still(0), _still(1)])
    report = check_trajectory(traj, HC10, YRC)
    accel = [w for w in report.warnings if w.kind == "acceleration"]
    assert [w.axis for w in accel] == ["joint_4_r"]
    assert accel[0].value > 30
    # the same move over 3 s (0.33 rad/s²) is clear
    assert (
        check_trajectory(_traj([0.0, 3.0], [START, goal], [_still(0)] * 2), HC10, YRC).warnings
        == []
    )


def test_increment_above_the_axis_maximum_is_a_warning() -> None:
    goal = list(START)
    goal[0] += 0.3
    fast = _still(0)
    fast[0] = 2.9  # trunc → 2 ≤ 2.27: MotoROS accepts it, but 2.9 rad/s > the axis maximum
    traj = _traj([0.0, 0.2, 0.4], [START, goal, goal], [_still(0), fast, _still(0)])
    report = check_trajectory(traj, HC10, YRC)
    assert report.accepted
    assert "increment" in {w.kind for w in report.warnings}


LIMIT_CLEARANCE = 0.01
"""rad kept between a generated waypoint and a joint limit."""

_WAYPOINT = st.lists(
    st.floats(-0.6, 0.6, allow_nan=False), min_size=len(NAMES), max_size=len(NAMES)
)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(_WAYPOINT, min_size=1, max_size=3),
    st.floats(0.2, 1.0),
    st.floats(0.2, 1.0),
)
def test_planned_waypoints_stay_within_limits_pass_check_and_reach_the_goal(
    offsets: list[list[float]], vscale: float, ascale: float
) -> None:
    lower = np.array([a.lower for a in HC10.groups[0].axes])
    upper = np.array([a.upper for a in HC10.groups[0].axes])
    # Waypoints at least LIMIT_CLEARANCE inside the limits: with one exactly on a limit
    # the cubic between two samples can pass it by a few pulses (docs/trajectories.md;
    # check flags it).
    waypoints = [np.array(START)] + [
        np.clip(np.array(START) + np.array(o), lower + LIMIT_CLEARANCE, upper - LIMIT_CLEARANCE)
        for o in offsets
    ]
    if all(np.max(np.abs(w - waypoints[0])) <= MIN_WAYPOINT_STEP for w in waypoints[1:]):
        return  # nothing to plan (plan_waypoints says so: tested below)
    traj = plan_waypoints(
        waypoints, HC10, YRC, velocity_scaling=vscale, acceleration_scaling=ascale
    )
    vmax = np.array([a.max_velocity for a in HC10.groups[0].axes])
    assert np.all(np.abs(traj.velocities) <= vmax * vscale)
    assert np.all((traj.positions >= lower) & (traj.positions <= upper))
    report = check_trajectory(traj, HC10, YRC)
    assert report.exit_code == EXIT_OK, report.to_json()
    outcome = asyncio.run(run_on_twin(traj))
    assert outcome.refused is None
    goal_pulses = np.array(AXES.take(to_pulses(tuple(waypoints[-1]), AXES)))
    final = np.array(outcome.commands[-1][0])[list(AXES.axis_slots)]
    assert np.all(np.abs(final - goal_pulses) <= 1)


def test_planning_errors_say_what_is_wrong() -> None:
    with pytest.raises(WaypointPlanningError, match="same position"):
        plan_waypoints([START, START], HC10, YRC)
    outside = list(START)
    outside[2] = -0.5
    with pytest.raises(WaypointPlanningError, match=r"joint_3_u = -0\.5 rad is outside"):
        plan_waypoints([START, outside], HC10, YRC)
    with pytest.raises(WaypointPlanningError, match="velocity scaling"):
        plan_waypoints([START, START], HC10, YRC, velocity_scaling=1.5)


def test_tiny_waypoint_steps_are_held_still() -> None:
    tiny = list(START)
    tiny[4] = 0.5
    tiny[5] = 5e-324
    traj = plan_waypoints([START, tiny, START], HC10, YRC)
    assert np.all(traj.positions[:, 5] == 0.0)
    assert check_trajectory(traj, HC10, YRC).exit_code == EXIT_OK


def test_multi_group_sda10f_planned_checked_and_matches_the_twin() -> None:
    sda = robot_model("sda10f")
    dx200 = controller_model("dx200")
    start = np.array(asyncio.run(twin_start("sda10f", "dx200")))
    goal = start.copy()
    goal[0] += 0.3  # left arm S
    goal[7 + 1] += 0.2  # right arm L
    goal[14] += 0.1  # torso
    traj = plan_waypoints([start, goal], sda, dx200)
    report = check_trajectory(traj, sda, dx200)
    assert report.exit_code == EXIT_OK, report.to_json()
    assert set(report.per_group) == {"R1", "R2", "B1", "B2"}
    outcome = asyncio.run(run_on_twin(traj, "sda10f", "dx200"))
    assert outcome.refused is None
    _assert_same_motion(report, outcome, sda, dx200)


FSU_PCT = 30
"""A cell's FSU joint-speed limit well below what the planned test trajectory uses."""


def _fsu_cell(tmp_path: Path, pct: int = FSU_PCT) -> Path:
    path = tmp_path / "fsu.toml"
    path.write_text(
        f'name = "fsu cell"\n[controller]\nmodel = "yrc1000"\nfsu_speed_limit_pct = {pct}\n'
        '[robot]\nmodel = "hc10"\n'
    )
    return path


def test_a_cell_with_an_fsu_limit_warns_where_the_built_in_model_passes_and_predicts_the_twin(
    tmp_path: Path,
) -> None:
    traj = there_and_back()
    built_in = check_trajectory(traj, HC10, YRC)
    assert built_in.exit_code == EXIT_OK, built_in.to_json()
    path = _fsu_cell(tmp_path)
    models = load_cell_models(path)
    report = check_against_cell(traj, models)
    assert report.exit_code == EXIT_WARNINGS
    [fsu] = [w for w in report.warnings if w.kind == "fsu"]
    clip = fsu_clip(AXES, FSU_PCT)[AXES.ros_to_slot[0]]
    assert (fsu.axis, fsu.limit) == ("joint_1_s", clip)
    assert fsu.value > clip
    assert report.increments > built_in.increments  # the FSU stretches the motion
    assert f"{FSU_PCT} %" in fsu.text
    outcome = asyncio.run(run_on_twin(traj, cell=load_cell(path)))
    assert outcome.refused is None
    _assert_same_motion(report, outcome, models.robot, models.controller)
    # the robot still ends where the trajectory does
    np.testing.assert_allclose(outcome.final, START, atol=1e-4)


def test_an_fsu_limit_the_trajectory_stays_under_changes_nothing(tmp_path: Path) -> None:
    goal = list(START)
    goal[0] += 0.2
    traj = plan_waypoints([START, goal], HC10, YRC, velocity_scaling=0.2)
    models = load_cell_models(_fsu_cell(tmp_path, 90))
    report = check_against_cell(traj, models)
    built_in = check_trajectory(traj, HC10, YRC)
    assert report.exit_code == EXIT_OK, report.to_json()
    assert report.increments == built_in.increments
    np.testing.assert_array_equal(report.per_group["R1"][1], built_in.per_group["R1"][1])


def _fsu_tick_by_tick(groups: list[tuple[GroupAxes, np.ndarray]], pct: int) -> list[np.ndarray]:
    """The FSU compensation one tick at a time, as the twin's IncMove task runs it
    (controller/incmove_task.py), without fsu_execution's skipping of unclipped rows."""
    clips = [[fsu_clip(a, pct)[s] for s in a.axis_slots] for a, _ in groups]
    maxes = [[a.max_increment[s] for s in a.axis_slots] for a, _ in groups]
    rows = [inc.tolist() for _, inc in groups]
    length = max(len(r) for r in rows)
    to_process = [[0] * len(c) for c in clips]
    processed = [[0] * len(c) for c in clips]
    out: list[list[list[int]]] = [[] for _ in groups]
    missing, k = False, 0
    while missing or k < length:
        if missing:
            sends = []
            for g in range(len(groups)):
                rest = [a - b for a, b in zip(to_process[g], processed[g], strict=True)]
                clamp = [abs(t) or m for t, m in zip(processed[g], maxes[g], strict=True)]
                sends.append([max(-c, min(c, r)) for r, c in zip(rest, clamp, strict=True)])
                to_process[g] = rest
        else:
            sends = [r[k] if k < len(r) else [0] * len(c) for r, c in zip(rows, clips, strict=True)]
            to_process = [list(x) for x in sends]
            k += 1
        missing = False
        for g, send in enumerate(sends):
            done = [max(-c, min(c, x)) for x, c in zip(send, clips[g], strict=True)]
            processed[g] = done
            out[g].append(done)
            missing = missing or done != to_process[g]
    return [np.array(o, dtype=np.int64) for o in out]


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 100), st.integers(0, 2**32 - 1))
def test_fsu_execution_equals_the_tick_by_tick_compensation(pct: int, seed: int) -> None:
    sda = robot_model("sda10f")
    dx200 = controller_model("dx200")
    rng = np.random.default_rng(seed)
    groups = []
    for gi, group in enumerate(sda.groups[:2]):
        axes = GroupAxes.from_model(group, dx200)
        top = np.array([axes.max_increment[s] for s in axes.axis_slots])
        length = 40 + 10 * gi
        inc = (rng.uniform(-1, 1, (length, len(top))) * top).astype(np.int64)
        inc[rng.uniform(size=length) < 0.5] //= 10  # stretches the FSU lets through
        groups.append((axes, inc))
    fast = fsu_execution(groups, pct)
    slow = _fsu_tick_by_tick(groups, pct)
    for f, s_, (_, inc) in zip(fast, slow, groups, strict=True):
        np.testing.assert_array_equal(f, s_)
        np.testing.assert_array_equal(f.sum(axis=0), inc.sum(axis=0))  # nothing is lost


def test_the_refusal_line_gives_value_and_limit_with_units() -> None:
    """``pymotoros check``'s "value …, limit …" line carries the unit of the subcode
    (issue 29: every number in an error has its unit)."""
    from pymotoros.cli.trajectory import render

    goal = list(START)
    goal[0] += 1.0
    fast = _still(0)
    fast[0] = 3.5
    speed = _traj([0.0, 1.0, 2.0], [START, goal, goal], [_still(0), fast, _still(2)])
    late = _traj([0.0, 14400.0], [START, START], [_still(0), _still(1)])
    for traj, unit in ((speed, "rad/s"), (late, "s")):
        report = check_trajectory(traj, HC10, YRC)
        assert report.refusal is not None
        text = render(report, traj, HC10, YRC)
        line = next(ln for ln in text.splitlines() if ln.startswith("  value "))
        r = report.refusal
        assert line == f"  value {r.value:.6g} {unit}, limit {r.limit:.6g} {unit}", text


def test_the_acceleration_warning_gives_the_rounding_allowance_its_unit() -> None:
    goal = list(START)
    goal[0] += 0.02  # 20 mrad in 8 ms from rest: far above joint_1_s's acceleration
    traj = _traj([0.0, 0.008, 0.5], [START, goal, goal], [_still(0), _still(1), _still(2)])
    report = check_trajectory(traj, HC10, YRC)
    texts = [w.text for w in report.warnings if w.kind == "acceleration"]
    assert texts, report.warnings
    assert re.search(r"above its [\d.]+ rad/s² \(plus [\d.]+ rad/s² for whole-pulse", texts[0])
