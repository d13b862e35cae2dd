"""The client plans around the obstacles of its cell file: ``move_joints(..., avoid=True)``
and ``plan(..., avoid=True)`` on the in-memory twin (issue 21 item 4, the client API).

The client reads the obstacles from the cell file it was given (MotoROS cannot report
them) and searches as ``pymotoros plan --avoid`` does; the twin, which checks every
tick's commanded position against the same obstacles, reports no contact on the way.
"""

from __future__ import annotations

from typing import Any

import pytest
from cell_twin import twin_of_cell

from pymotoros import PathBlockedError
from pymotoros.client import NotReadyError, PlanningError
from pymotoros.controller.cell import cell_from_dict
from pymotoros.kinematics.collision import world_for_cell
from pymotoros.models.cell import cell_models_from_dict
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.testing import Twin

BALL = {"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75]}
"""In the HC10's way when it swings axis S with L tilted forward."""
LEFT = [-0.8, 0.6, 0.0, 0.0, 0.0, 0.0]
RIGHT = [0.8, 0.6, 0.0, 0.0, 0.0, 0.0]
INSIDE = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]
"""The elbow inside the ball."""
DATA: dict[str, Any] = {
    "robot": {"model": "hc10"},
    "initial": {"joints": {"R1": LEFT}},
    "workspace": {"obstacles": [BALL]},
}


def _touches_on_the_way(a: list[float], b: list[float]) -> bool:
    world = world_for_cell(cell_models_from_dict(DATA))
    return bool(world.segment_contacts(a, b))


async def test_the_client_moves_around_the_ball_and_the_twin_feels_no_contact() -> None:
    assert _touches_on_the_way(LEFT, RIGHT)  # the straight swing goes through the ball
    async with Twin(cell_from_dict(DATA)) as the_twin:
        contacts: list[object] = []
        the_twin.on_tick(lambda: contacts.extend(the_twin.controller.workspace_contacts))
        async with the_twin.client(cell=cell_models_from_dict(DATA)) as client:
            await client.wait_for_state()
            await client.enable()
            result = await client.move_joints(RIGHT, avoid=True)
            assert list(result.final_positions) == pytest.approx(RIGHT, abs=1e-3)
            assert contacts == []
            snapshot = the_twin.controller.snapshot()
            assert snapshot.pfl == "idle"
            assert not snapshot.alarms
            assert len(result.trajectory.points) > 2
            # the plain move back goes through the ball: the guard refuses it, and forced
            # PFL stops it
            with pytest.raises(PathBlockedError, match="link_2_l touches obstacle 'ball'"):
                await client.move_joints(LEFT, speed_scale=0.5)
            with pytest.raises(NotReadyError) as info:
                await client.move_joints(LEFT, speed_scale=0.5, force=True)
            assert info.value.reason is NotReadySubcode.PFL_ACTIVE


async def test_a_blocked_goal_raises_path_blocked_naming_the_obstacle() -> None:
    async with twin_of_cell(DATA) as (client, the_twin):
        with pytest.raises(PathBlockedError) as info:
            await client.move_joints(INSIDE, avoid=True)
        assert str(info.value) == (
            "the goal is in collision: obstacle 'ball' (R1 link_2_l touches it)"
        )
        assert the_twin.controller.snapshot().workspace.contacts == ()
        # nothing was sent: the robot still stands at the start
        here = await client.current_positions()
        assert list(here) == pytest.approx(LEFT, abs=1e-4)


async def test_plan_with_avoid_returns_the_detour_without_moving() -> None:
    async with twin_of_cell(DATA, enable=False) as (client, _the_twin):
        start = await client.current_positions()
        planned = client.plan(start, RIGHT, avoid=True)
        direct = client.plan(start, RIGHT)
        assert planned.goal == pytest.approx(RIGHT)
        assert planned.duration > direct.duration  # the way round is longer
        world = world_for_cell(cell_models_from_dict(DATA))
        for a, b in zip(planned.points, planned.points[1:], strict=False):
            assert world.segment_contacts(a.positions, b.positions) == []


async def test_avoid_without_a_cell_says_what_it_needs() -> None:
    async with Twin(cell_from_dict(DATA)) as the_twin, the_twin.client() as client:
        await client.wait_for_state()  # the client knows robot and controller, no cell
        with pytest.raises(PlanningError, match=r"needs the cell's obstacles.*cell="):
            await client.move_joints(RIGHT, avoid=True)


async def test_the_following_monitor_measures_a_detour_along_its_path() -> None:
    """Progress along a detour is not its start-to-goal line (which a robot going round
    first leaves sideways or backwards): no false "slowed" there, either way round."""
    async with twin_of_cell(DATA) as (client, _the_twin):
        for goal in (RIGHT, LEFT):
            result = await client.move_joints(goal, avoid=True)
            assert list(result.final_positions) == pytest.approx(goal, abs=1e-3)
            assert not result.following.slowed
            assert result.following.max_lag_s < 0.1
