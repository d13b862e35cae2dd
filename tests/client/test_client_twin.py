"""The client against the real virtual controller: in memory (the twin), and once over TCP.

The twin (:mod:`pymotoros.testing`) runs the controller and the MotoROS server handlers
in virtual time; the last test drives ``pymotoros sim`` over TCP, as users do.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import pytest
from client_sim import running_sim

from first_script import move_b_and_set_an_output
from load_proof import Stopwatch
from pymotoros.client import (
    JointTrajectory,
    MoveResult,
    NotReadyError,
    RobotClient,
    SyncRobotClient,
)
from pymotoros.client.planning import TrajectoryPoint
from pymotoros.client.srdf import parse_srdf
from pymotoros.controller import PendantMode, VirtualController
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.testing import Twin, sync_twin

SRDF = Path(__file__).resolve().parents[2] / "examples" / "hc10.srdf"
TOLERANCE = 1e-3
LONG_MOVE_S = 60.0
"""The issue's yardstick: a minute of motion."""
VIRTUAL_SPEEDUP_AT_LEAST = 10.0
"""How much less CPU time than motion time the move must take (issue 8's "well under a
second" is measured quietly, by ``bench/bench_minute_move.py``: 0.7-1.0 s, 60-90x real
time, figures in docs/benchmarks.md). CPU time, so a loaded runner cannot fail it; the
wall clock, less the time spent waiting for a CPU, is held only to half the motion time,
which a twin that waited on it misses by far (docs/testing.md)."""
MOVEIT_LIKE_SPACING_S = 0.1
"""Points every 100 ms, as a time-parameterised MoveIt plan typically has them."""


def _off(goal: tuple[float, ...], actual: tuple[float, ...]) -> float:
    return max(abs(a - b) for a, b in zip(goal, actual, strict=True))


async def test_named_poses_in_order_end_within_a_milliradian(client: RobotClient) -> None:
    await client.enable()
    poses = parse_srdf(SRDF)
    for pose in poses:
        result = await client.move_named(pose.name, srdf=SRDF)
        goal = pose.positions_for(client.robot.groups[0])
        assert _off(goal, result.final_positions) < TOLERANCE
        fb = client.feedback(0)
        assert fb is not None
        assert _off(goal, fb.positions) < TOLERANCE
    result = await client.move_named("home")
    assert _off((0.0,) * 6, result.final_positions) < TOLERANCE


async def _timed_execute(
    client: RobotClient, plan: JointTrajectory
) -> tuple[MoveResult, float, float]:
    """``client.execute(plan)``: its result, the CPU time it took (which a loaded runner
    does not stretch) and the wall time less the waits for a CPU (tests/load_proof.py)."""
    cpu_start, watch = time.process_time(), Stopwatch()
    result = await client.execute(plan)
    return result, time.process_time() - cpu_start, watch.unloaded()


async def test_a_minute_long_trajectory_runs_in_virtual_time(
    client: RobotClient, cell: Twin
) -> None:
    """A planned move of over a minute, with points as dense as a MoveIt plan's."""
    await client.enable()
    here = await client.current_positions()
    goal = (1.0, 0.5, 0.3, 0.2, -1.0, 0.5)
    minute = client.plan(here, goal, speed_scale=0.007, sample_period=MOVEIT_LIKE_SPACING_S)
    assert minute.duration >= LONG_MOVE_S
    assert len(minute.points) >= LONG_MOVE_S / MOVEIT_LIKE_SPACING_S
    virtual_start = cell.clock.now()
    result, cpu, wall = await _timed_execute(client, minute)
    assert _off(goal, result.final_positions) < TOLERANCE
    assert result.stream.points == len(minute.points)
    # Paced offers: each point offered when MotoROS can take it, about once (a fixed
    # 2 ms back-off costs dozens of BUSY per 100 ms point; issue 22).
    assert result.stream.offers <= 2 * len(minute.points)
    virtual = cell.clock.now() - virtual_start
    assert virtual >= LONG_MOVE_S
    # The work in CPU time, which a loaded runner does not stretch; and the wall clock
    # (less the wait for a CPU, tests/load_proof.py) only against a twin that waited on
    # it (it would need all 60 s).
    assert cpu < virtual / VIRTUAL_SPEEDUP_AT_LEAST, f"{virtual:.1f} s of motion: {cpu:.2f} s CPU"
    assert wall < virtual / 2, f"{virtual:.1f} s of motion took {wall:.2f} s"


async def test_a_long_planned_move_runs_much_faster_than_real_time(
    client: RobotClient, cell: Twin
) -> None:
    goal = (0.6, 0.3, 0.2, 0.1, -0.6, 0.3)
    await client.enable()
    here = await client.current_positions()
    plan = client.plan(here, goal, speed_scale=0.02)
    assert plan.duration > 10.0
    result, cpu, wall = await _timed_execute(client, plan)
    assert _off(goal, result.final_positions) < TOLERANCE
    assert result.stream.points == len(plan.points)
    assert result.stream.offers <= 2 * len(plan.points)  # BUSY retries paced (issue 22)
    assert not result.following.slowed
    assert cpu < plan.duration / 4  # the work (CPU time: load does not stretch it)
    assert wall < 0.9 * plan.duration  # not paced by the wall clock (less CPU waits)


def _estop(c: VirtualController) -> None:
    c.press_estop(True)


def _alarm(c: VirtualController) -> None:
    c.raise_alarm(4100, 1, "test")


def _teach(c: VirtualController) -> None:
    c.set_mode(PendantMode.TEACH)


def _remote_off(c: VirtualController) -> None:
    c.set_remote(False)


def _servo_off(c: VirtualController) -> None:
    c.set_servo(False)


def _hold(c: VirtualController) -> None:
    c.set_hold(True)


@pytest.mark.parametrize(
    ("action", "reason", "enable_refused"),
    [
        (_estop, NotReadySubcode.ESTOP, True),
        (_alarm, NotReadySubcode.ALARM, False),
        (_teach, NotReadySubcode.NOT_PLAY, True),
        (_remote_off, NotReadySubcode.NOT_REMOTE, True),
        (_servo_off, NotReadySubcode.SERVO_OFF, False),
        (_hold, NotReadySubcode.HOLD, True),
    ],
)
async def test_not_ready_reasons(
    client: RobotClient,
    cell: Twin,
    action: Callable[[VirtualController], None],
    reason: NotReadySubcode,
    enable_refused: bool,
) -> None:
    await client.enable()
    seen = client.state.status_count
    action(cell.controller)
    # A status sent after the operator's action: the cached one may predate it, and
    # MotoROS (like us) reads the controller's signals every 10 ms, so only a fresh
    # "motion impossible" says that CHECK_MOTION_READY will give the reason.
    await client.wait_until(
        lambda s: s.status_count > seen and s.status is not None and not s.status.motion_possible,
        5.0,
        "a fresh status saying motion is impossible",
    )
    readiness = await client.check_motion_ready()
    assert readiness.reason is reason
    assert readiness.remedy
    start = client.state.positions(0)
    assert start is not None
    traj = JointTrajectory((TrajectoryPoint(0.0, start, (0.0,) * 6),), 0.0)
    with pytest.raises(NotReadyError) as info:
        await client.execute(traj)
    assert info.value.reason is reason
    if enable_refused:
        with pytest.raises(NotReadyError) as info:
            await client.enable()
        assert info.value.reason is reason
    else:
        await client.enable()  # START_TRAJ_MODE resets alarms and switches servo power on
        assert (await client.check_motion_ready()).ready


def test_blocking_facade_on_the_twin() -> None:
    with sync_twin(robot="hc10") as (robot, the_twin):
        robot.enable()
        start = the_twin.clock.now()
        result = robot.move_joints([0.0, 0.0, 0.0, 0.0, -1.57, 0.0])
        assert abs(result.final_positions[4] + 1.57) < TOLERANCE
        assert the_twin.clock.now() - start >= result.trajectory.duration
        robot.write_io_bit(10020, 1)
        assert robot.read_io_bit(10020) == 1
        plan = robot.plan(robot.current_positions(), (0.0,) * 6)
        assert robot.execute(plan).final_positions == pytest.approx((0.0,) * 6, abs=TOLERANCE)


def test_blocking_facade_over_tcp() -> None:
    with (
        running_sim() as sim,
        SyncRobotClient(**sim.client_options()) as robot,
    ):
        move_b_and_set_an_output(robot, -1.57)
        states = robot.states()
        assert next(states).count > 0
        states.close()
        robot.move_named("home")
