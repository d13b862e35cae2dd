"""Planning around obstacles (OMPL): the result passes the check; a blocked goal is refused."""

from __future__ import annotations

from typing import Any

import pytest

from pymotoros.kinematics.collision import world_for_cell
from pymotoros.models.cell import CellModels, cell_models_from_dict
from pymotoros.trajectory.avoid import PathBlockedError, avoid_waypoints, plan_avoiding
from pymotoros.trajectory.check import check_against_cell
from pymotoros.trajectory.collisions import find_collisions
from pymotoros.trajectory.planning import plan_waypoints

BALL = {"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75]}
LEFT = [-0.8, 0.6, 0.0, 0.0, 0.0, 0.0]
RIGHT = [0.8, 0.6, 0.0, 0.0, 0.0, 0.0]


def _cell(*obstacles: dict[str, Any]) -> CellModels:
    return cell_models_from_dict(
        {"robot": {"model": "hc10"}, "workspace": {"obstacles": list(obstacles)}}
    )


def _collisions(cell: CellModels, traj: Any) -> list[Any]:
    report = check_against_cell(traj, cell)
    assert report.accepted
    return find_collisions(traj, cell, report.per_group, world_for_cell(cell))


def test_a_detour_around_the_ball_passes_the_check() -> None:
    cell = _cell(BALL)
    direct = plan_waypoints([LEFT, RIGHT], cell.robot, cell.controller)
    assert _collisions(cell, direct)  # the straight swing hits it
    traj = plan_avoiding([LEFT, RIGHT], cell, world_for_cell(cell))
    assert _collisions(cell, traj) == []
    assert traj.positions[0].tolist() == pytest.approx(LEFT)
    assert traj.positions[-1].tolist() == pytest.approx(RIGHT)


def test_a_free_straight_way_is_kept_as_it_is() -> None:
    cell = _cell(BALL)
    way = avoid_waypoints([[0.0] * 6, [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0]], cell, world_for_cell(cell))
    assert len(way) == 2


def test_a_goal_inside_an_obstacle_is_refused_naming_it() -> None:
    cell = _cell(BALL)
    with pytest.raises(PathBlockedError, match="waypoint 1 is in collision: obstacle 'ball'"):
        avoid_waypoints([[0.0] * 6, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]], cell, world_for_cell(cell))


def test_when_the_planner_finds_nothing_the_refusal_names_what_is_in_the_way(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import pymotoros.kinematics.path_search as search

    monkeypatch.setattr(search, "_plan_segment", lambda *args: [])
    cell = _cell(BALL)
    with pytest.raises(PathBlockedError) as info:
        avoid_waypoints([LEFT, RIGHT], cell, world_for_cell(cell), time_limit_s=0.5)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("no collision-free path from waypoint 0 to 1 found in 0.5 s: ")
    assert "obstacle 'ball' (R1 link_2_l touches it) is in the way" in message


async def test_the_twin_runs_the_detour_to_the_goal_without_contact() -> None:
    from pymotoros.controller.cell import cell_from_dict

    from .twin_run import run_on_twin

    data = {
        "robot": {"model": "hc10"},
        "initial": {"joints": {"R1": LEFT}},
        "workspace": {"obstacles": [BALL]},
    }
    cell = _cell(BALL)
    traj = plan_avoiding([LEFT, RIGHT], cell, world_for_cell(cell))
    outcome = await run_on_twin(traj, cell=cell_from_dict(data))
    assert outcome.refused is None
    assert list(outcome.final) == pytest.approx(RIGHT, abs=1e-4)
    # and the straight swing is stopped by the ball (PFL: the twin sees the contact)
    direct = await run_on_twin(
        plan_waypoints([LEFT, RIGHT], cell.robot, cell.controller), cell=cell_from_dict(data)
    )
    assert direct.refused is not None
