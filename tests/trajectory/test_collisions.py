"""Collisions along a checked trajectory, at the controller's own increments."""

from __future__ import annotations

import math
from typing import Any

import pytest

from pymotoros.kinematics.collision import world_for_cell
from pymotoros.models.cell import CellModels, cell_models_from_dict
from pymotoros.trajectory.check import EXIT_REFUSED, check_against_cell
from pymotoros.trajectory.collisions import find_collisions
from pymotoros.trajectory.files import Trajectory
from pymotoros.trajectory.planning import plan_waypoints

BALL = {"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75]}


def _cell(*obstacles: dict[str, Any]) -> CellModels:
    return cell_models_from_dict(
        {"robot": {"model": "hc10"}, "workspace": {"obstacles": list(obstacles)}}
    )


def _plan(cell: CellModels, *rows: list[float]) -> Trajectory:
    return plan_waypoints([list(r) for r in rows], cell.robot, cell.controller)


def _collisions(cell: CellModels, traj: Trajectory) -> list[Any]:
    report = check_against_cell(traj, cell)
    return find_collisions(traj, cell, report.per_group, world_for_cell(cell))


def test_a_swing_through_a_ball_reports_it_once_with_link_and_time() -> None:
    cell = _cell(BALL)
    traj = _plan(cell, [0.0] * 6, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    found = _collisions(cell, traj)
    # the upper arm meets it first; the forearm, folded beside it, follows
    assert [(c.obstacle, c.link) for c in found] == [("ball", "link_2_l"), ("ball", "link_3_u")]
    hit = found[0]
    assert 0.0 < hit.time_s < hit.end_s <= traj.duration + 0.01
    assert hit.depth_mm > 50  # the arm passes right through it
    assert not hit.self_collision


def test_the_time_is_the_first_tick_in_contact() -> None:
    cell = _cell(BALL)
    traj = _plan(cell, [0.0] * 6, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    report = check_against_cell(traj, cell)
    world = world_for_cell(cell)
    hit = find_collisions(traj, cell, report.per_group, world)[0]
    # brute force: every tick
    from pymotoros.trajectory.collisions import joint_paths

    times, paths = joint_paths(traj, cell, report.per_group)
    first = next(k for k in range(len(times)) if world.contacts([paths[0][k]]))
    assert hit.time_s == pytest.approx(times[first])


def test_a_path_that_misses_everything_has_no_collisions() -> None:
    cell = _cell(BALL, {"name": "table", "box": [1.2, 0.8, 0.05], "xyz": [0.6, 0.0, -0.03]})
    traj = _plan(cell, [0.0] * 6, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert _collisions(cell, traj) == []


def test_a_graze_between_two_points_is_found() -> None:
    # both points are clear; the straight joint path between them crosses the ball
    cell = _cell(BALL)
    a = [-0.8, 0.6, 0.0, 0.0, 0.0, 0.0]
    b = [0.8, 0.6, 0.0, 0.0, 0.0, 0.0]
    world = world_for_cell(cell)
    assert world.contacts([a]) == []
    assert world.contacts([b]) == []
    traj = _plan(cell, a, b)
    assert {c.obstacle for c in _collisions(cell, traj)} == {"ball"}


def test_self_collision_along_the_path() -> None:
    cell = _cell({"name": "far", "sphere": 0.05, "xyz": [3.0, 3.0, 3.0]})
    bent = [-1.13, -2.4, 5.66, -2.15, 1.49, 1.0]
    traj = _plan(cell, [0.0] * 6, bent)
    found = _collisions(cell, traj)
    assert found
    assert all(c.self_collision for c in found)
    assert ("base_link", "link_3_u") in {(c.obstacle, c.link) for c in found}


def test_the_report_carries_collisions_into_json_and_exit_code() -> None:
    cell = _cell(BALL)
    traj = _plan(cell, [0.0] * 6, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    report = check_against_cell(traj, cell)
    assert report.exit_code != EXIT_REFUSED
    report.collisions = _collisions(cell, traj)
    assert report.exit_code == EXIT_REFUSED
    entry = report.to_json()["collisions"][0]
    assert entry["obstacle"] == "ball"
    assert entry["link"] == "link_2_l"
    assert math.isfinite(entry["time_s"])


@pytest.mark.parametrize(
    "rows",
    [
        ([-0.8, 0.6, 0.0, 0.0, 0.0, 0.0], [0.8, 0.6, 0.0, 0.0, 0.0, 0.0]),
        ([0.0] * 6, [0.3, 1.0, 0.2, 0.5, -1.0, 0.0], [-0.5, 0.2, 0.0, 0.0, 0.0, 0.0]),
        ([0.0] * 6, [-1.13, -2.4, 5.66, -2.15, 1.49, 1.0]),
    ],
)
def test_skipping_ticks_finds_what_checking_every_tick_finds(rows: tuple[list[float], ...]) -> None:
    from pymotoros.trajectory.collisions import joint_paths

    cell = _cell(BALL, {"name": "post", "cylinder": [0.05, 1.5], "xyz": [0.5, -0.4, 0.75]})
    traj = _plan(cell, *rows)
    report = check_against_cell(traj, cell)
    world = world_for_cell(cell)
    found = {(c.link, c.obstacle, round(c.time_s, 6)) for c in _collisions(cell, traj)}
    times, paths = joint_paths(traj, cell, report.per_group)
    every: set[tuple[str, str, float]] = set()
    before: set[tuple[str, str]] = set()
    for k in range(len(times)):
        now = {(c.link, c.obstacle) for c in world.all_contacts([paths[0][k]])}
        every.update((link, obstacle, round(float(times[k]), 6)) for link, obstacle in now - before)
        before = now
    assert found == every
