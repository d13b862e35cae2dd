"""A ``motoman_driver``-style stream gives the twin's client lint nothing to say in normal
use (issue 31): robot_enable, CHECK_MOTION_READY, JOINT_TRAJ_PT_FULL points 0, 1, 2 …
resent after BUSY, over TCP, with the state node connected first. The driver is the
stand-in of :mod:`.ros_driver_like`, behind pass-through proxies."""

from __future__ import annotations

from pymotoros.pytest_plugin import RunningTwin

from .ros_driver_like import TransferState
from .test_ros_driver_reconnect import (
    GOAL,
    MOVE_TIMEOUT_S,
    cell_with_driver,
    distance,
)

HOME = (0.0,) * 6


async def test_two_goals_of_the_driver_give_no_finding(pymotoros_twin: RunningTwin) -> None:
    async with cell_with_driver(pymotoros_twin) as cell:
        motion = cell.motion
        assert await motion.enable(), motion.recorder.notes  # robot_enable
        for goal in (GOAL, HOME, GOAL):
            points = cell.plan(goal, speed_scale=1.0)
            assert len(points) > 10
            assert await motion.execute(points), motion.recorder.notes
            await motion.recorder.wait_until(
                lambda: motion.state is TransferState.IDLE, timeout_s=MOVE_TIMEOUT_S
            )
            assert motion.aborted is None
            ended_at = await cell.at_rest()
            assert distance(ended_at, goal) < 1e-3
            await cell.state_caught_up(ended_at)
        assert motion.conn.connections == 1
    assert pymotoros_twin.lint_findings() == []
