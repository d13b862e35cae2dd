"""Issue 29, item 2: one move at a time, said plainly.

A second move on a client while one runs is refused at once (nothing sent) with a
typed error that says what runs and how to wait for it or stop it; a second client
that MotoROS's one-motion-connection rule shuts out is told that rule.
"""

from __future__ import annotations

import asyncio
import re

import pytest

from pymotoros import MoveInProgressError as FrontDoorError
from pymotoros.client import ConnectionLostError, MoveInProgressError, RobotClient
from pymotoros.testing import Twin

GOAL = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
OTHER = (-1.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_the_error_is_at_the_front_door() -> None:
    assert FrontDoorError is MoveInProgressError


async def test_a_second_move_is_refused_at_once_and_the_first_goes_on(
    pair: tuple[RobotClient, Twin],
) -> None:
    client, _the_twin = pair
    await client.enable()
    first, second = await asyncio.gather(
        client.move_joints(GOAL), client.move_joints(OTHER), return_exceptions=True
    )
    assert not isinstance(first, BaseException), first
    assert abs(first.final_positions[0] - GOAL[0]) < 1e-3
    assert isinstance(second, MoveInProgressError)
    text = str(second)
    assert "move_joints() refused" in text
    assert "still running" in text
    assert "await" in text  # how to wait for it
    assert "stop()" in text  # how to stop it
    assert abs((client.state.positions(0) or (0.0,))[0] - GOAL[0]) < 1e-3


async def test_every_move_entry_is_refused_while_one_runs(pair: tuple[RobotClient, Twin]) -> None:
    client, the_twin = pair
    await client.enable()
    moving = asyncio.create_task(client.move_joints(GOAL))
    await the_twin.sleep(0.2)
    start = client.state.positions(0) or ()
    plan = client.plan(start, OTHER)
    attempts = {
        "execute": client.execute(plan),
        "move_joints": client.move_joints(OTHER),
        "move_named": client.move_named("home"),
        "move_pose": client.move_pose((0.5, 0.0, 0.5, 3.14, 0.0, 0.0), tool=0),
        "move_linear": client.move_linear((0.5, 0.0, 0.5, 3.14, 0.0, 0.0), tool=0),
        "move_relative": client.move_relative(dz=0.01, tool=0),
    }
    for name, attempt in attempts.items():
        t0 = the_twin.clock.now()
        with pytest.raises(MoveInProgressError, match=rf"{name}\(\) refused"):
            await attempt
        assert the_twin.clock.now() == t0  # at once: no wait, nothing sent
    result = await moving
    assert abs(result.final_positions[0] - GOAL[0]) < 1e-3


async def test_the_same_client_moves_again_once_the_first_move_ended(
    pair: tuple[RobotClient, Twin],
) -> None:
    client, _ = pair
    await client.enable()
    await client.move_joints(GOAL)
    result = await client.move_joints(OTHER)
    assert abs(result.final_positions[0] - OTHER[0]) < 1e-3


async def test_a_second_client_is_told_the_one_motion_connection_rule() -> None:
    async with Twin(robot="hc10") as the_twin:
        first = the_twin.client(timeout_s=2.0)
        await first.connect()
        await first.wait_for_state()
        await first.enable()
        moving = asyncio.create_task(first.move_joints((2.0, 0, 0, 0, 0, 0)))
        await the_twin.sleep(0.3)
        second = the_twin.client(timeout_s=2.0)
        # Connecting sends STOP_MOTION at once (a lost connection's queued increments would
        # run otherwise, §2.2): the controller closes the newcomer before it answers that.
        with pytest.raises(ConnectionLostError) as info:
            await second.connect(state=False, io=False)
        text = str(info.value)
        assert "MotoROS takes one motion connection" in text
        assert "another client holds the motion connection" in text
        assert "Wait until its move has ended" in text
        await second.close()
        result = await moving  # the first client's move is not disturbed
        assert abs(result.final_positions[0] - 2.0) < 1e-3
        await first.close()


async def _moving(client: RobotClient, the_twin: Twin) -> None:
    for _ in range(200):
        status = client.state.status
        if status is not None and status.in_motion:
            return
        await the_twin.sleep(0.01)
    raise AssertionError("the robot did not start moving")


async def test_a_robot_stopped_away_from_the_goal_is_told_in_rad_with_the_joint(
    pair: tuple[RobotClient, Twin],
) -> None:
    """Issue 29: "came to rest 1.00000 from the goal" had no unit and no joint."""
    client, the_twin = pair
    await client.enable()
    move = asyncio.create_task(client.move_joints(GOAL, speed_scale=0.3))
    await _moving(client, the_twin)
    await client.stop_motion()  # what the robot sees of a second client's STOP_MOTION
    with pytest.raises(Exception, match="from the goal") as info:
        await move
    text = str(info.value)
    assert type(info.value).__name__ == "MotionIncompleteError"
    assert re.search(r"came to rest \d+\.\d{4} rad \(joint_1_s\) from the goal", text), text
    assert re.search(r"at \[-?\d+\.\d{4}, .*\] rad", text), text


async def test_an_estop_mid_move_says_the_distance_in_rad(pair: tuple[RobotClient, Twin]) -> None:
    client, the_twin = pair
    await client.enable()
    start = await client.current_positions()
    plan = client.plan(start, GOAL, speed_scale=0.3)
    move = asyncio.create_task(client.execute(plan))
    await the_twin.sleep(plan.duration - 0.05)  # every point sent: waiting for the end
    the_twin.controller.press_estop(True)
    with pytest.raises(Exception, match="from the goal") as info:
        await move
    assert re.search(r"stopped \d+\.\d{4} rad \(joint_1_s\) from the goal", str(info.value))


async def test_an_idle_client_whose_motion_connection_was_taken_over_is_told_why() -> None:
    """MotoROS hands an idle motion connection to a newcomer (§2.2): the older client's
    next request says so instead of a bare "closed by the controller"."""
    async with Twin(robot="hc10") as the_twin:
        first = the_twin.client(timeout_s=2.0)
        await first.connect(state=False, io=False)
        await first.check_motion_ready()  # answered: an established connection
        second = the_twin.client(timeout_s=2.0)
        await second.connect(state=False, io=False)
        await second.check_motion_ready()
        with pytest.raises(ConnectionLostError) as info:
            await first.check_motion_ready()
        text = str(info.value)
        assert "MotoROS takes one motion connection" in text
        assert "takes it over and the older connection is closed" in text
        await first.close()
        await second.close()
