"""The client against the real virtual controller (``pymotoros sim`` on port 0)."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from client_sim import Sim, running_sim

from pymotoros.client import (
    BusyTimeoutError,
    ConnectionLostError,
    IoError,
    MotionIncompleteError,
    NotReadyError,
    RobotClient,
    SpeedLimitError,
    StartPositionError,
    SyncRobotClient,
)
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.srdf import parse_srdf
from pymotoros.protocol.constants import IoResultCode, NotReadySubcode

SRDF = Path(__file__).resolve().parents[2] / "examples" / "hc10.srdf"
TOLERANCE = 1e-3


@pytest.fixture(scope="module")
def sim() -> Iterator[Sim]:
    with running_sim() as s:
        yield s


@pytest.fixture(autouse=True)
def _operator_back_to_normal(request: pytest.FixtureRequest) -> Iterator[None]:
    yield
    if "sim" in request.fixturenames:
        s: Sim = request.getfixturevalue("sim")
        if s.process.poll() is None:
            for path, body in (
                ("/api/estop", {"pressed": False}),
                ("/api/hold", {"on": False}),
                ("/api/mode", {"mode": "play"}),
                ("/api/remote", {"on": True}),
                ("/api/reset", {}),
            ):
                s.api(path, body)


@pytest.fixture
async def robot(sim: Sim) -> Any:
    async with RobotClient(**sim.client_options(), timeout_s=5.0) as c:
        await c.wait_for_state()
        await c.enable()
        yield c


def _off(goal: tuple[float, ...], actual: tuple[float, ...]) -> float:
    return max(abs(a - b) for a, b in zip(goal, actual, strict=True))


async def test_named_poses_in_order_end_within_a_milliradian(robot: RobotClient) -> None:
    poses = parse_srdf(SRDF)
    for pose in poses:
        result = await robot.move_named(pose.name, srdf=SRDF)
        goal = pose.positions_for(robot.robot.groups[0])
        assert _off(goal, result.final_positions) < TOLERANCE
        fb = robot.feedback(0)
        assert fb is not None
        assert _off(goal, fb.positions) < TOLERANCE
    result = await robot.move_named("home")
    assert _off((0.0,) * 6, result.final_positions) < TOLERANCE


async def test_back_to_back_moves_need_no_waiting(robot: RobotClient) -> None:
    goals = [(0.2, 0.1, 0.3, 0.0, -1.57, 0.0), (0.0, 0.0, 0.0, 0.0, -1.57, 0.0), (0.0,) * 6]
    for goal in goals:
        result = await robot.move_joints(goal, speed_scale=1.0)
        assert _off(goal, result.final_positions) < TOLERANCE
        assert result.stream.busy_replies >= 0


@pytest.mark.parametrize(
    ("path", "body", "reason", "enable_refused"),
    [
        ("/api/estop", {"pressed": True}, NotReadySubcode.ESTOP, True),
        ("/api/alarm", {"code": 4100, "subcode": 1, "text": "test"}, NotReadySubcode.ALARM, False),
        ("/api/mode", {"mode": "teach"}, NotReadySubcode.NOT_PLAY, True),
        ("/api/remote", {"on": False}, NotReadySubcode.NOT_REMOTE, True),
        ("/api/servo", {"on": False}, NotReadySubcode.SERVO_OFF, False),
        ("/api/hold", {"on": True}, NotReadySubcode.HOLD, True),
    ],
)
async def test_not_ready_reasons(
    sim: Sim,
    robot: RobotClient,
    path: str,
    body: dict[str, Any],
    reason: NotReadySubcode,
    enable_refused: bool,
) -> None:
    seen = robot.state.status_count
    sim.api(path, body)
    # A status sent after the operator's action: the cached one may predate enable(), and
    # MotoROS (like us) reads the controller's signals every 10 ms, so only a fresh
    # "motion impossible" says that CHECK_MOTION_READY will give the reason.
    await robot.wait_until(
        lambda s: s.status_count > seen and s.status is not None and not s.status.motion_possible,
        5.0,
        "a fresh status saying motion is impossible",
    )
    readiness = await robot.check_motion_ready()
    assert readiness.reason is reason
    assert readiness.remedy
    start = robot.state.positions(0)
    assert start is not None
    traj = JointTrajectory((TrajectoryPoint(0.0, start, (0.0,) * 6),), 0.0)
    with pytest.raises(NotReadyError) as info:
        await robot.execute(traj)
    assert info.value.reason is reason
    if enable_refused:
        with pytest.raises(NotReadyError) as info:
            await robot.enable()
        assert info.value.reason is reason
    else:
        await robot.enable()  # START_TRAJ_MODE resets alarms and switches servo power on
        assert (await robot.check_motion_ready()).ready


async def test_wrong_start_point_is_3011_with_numbers(robot: RobotClient) -> None:
    here = await robot.current_positions()
    off = list(here)
    off[4] += 0.01
    traj = JointTrajectory(
        (TrajectoryPoint(0.0, tuple(off), (0.0,) * 6), TrajectoryPoint(1.0, here, (0.0,) * 6)), 1.0
    )
    with pytest.raises(StartPositionError) as info:
        await robot.execute(traj)
    (dev,) = info.value.deviations
    assert dev.name == "joint_5_b"
    assert dev.pulses is not None
    assert dev.pulses > 30
    assert dev.difference == pytest.approx(0.01, abs=1e-4)


async def test_too_fast_is_3013(robot: RobotClient) -> None:
    here = await robot.current_positions()
    fast = (0.0, 0.0, 0.0, 0.0, 0.0, 6.0)
    traj = JointTrajectory(
        (TrajectoryPoint(0.0, here, (0.0,) * 6), TrajectoryPoint(0.5, here, fast)), 0.5
    )
    with pytest.raises(SpeedLimitError) as info:
        await robot.execute(traj, check_speed=False)
    assert info.value.point == 1
    assert info.value.deviations[0].name == "joint_6_t"
    await robot.stop_motion()


async def test_busy_storm_gives_busy_timeout(robot: RobotClient) -> None:
    # A long move at a fine grid fills the 200-entry queue: BUSY until it drains.
    here = await robot.current_positions()
    goal = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    traj = robot.plan(here, goal, speed_scale=0.2, sample_period=0.004)
    with pytest.raises(BusyTimeoutError) as info:
        await robot.execute(traj, busy_timeout_s=0.002)
    assert info.value.point is not None
    assert info.value.point > 0
    await robot.stop_motion()


async def test_queue_count_while_moving_then_zero(robot: RobotClient) -> None:
    counts: list[int] = []
    move = asyncio.create_task(robot.move_joints((0.4, 0.0, 0.0, 0.0, 0.0, 0.0), speed_scale=0.5))
    await robot.wait_until(lambda s: bool(s.status and s.status.in_motion), 5.0, "motion")
    counts.append(await robot.queue_count())
    await move
    assert counts[0] > 0
    assert await robot.queue_count() == 0
    await robot.move_named("home")


async def test_stop_motion_mid_move_is_reported(robot: RobotClient) -> None:
    move = asyncio.create_task(robot.move_joints((0.5, 0.0, 0.0, 0.0, 0.0, 0.0), speed_scale=0.3))
    await robot.wait_until(lambda s: bool(s.status and s.status.in_motion), 5.0, "motion")
    await robot.stop_motion()
    async with asyncio.timeout(15):
        with pytest.raises(MotionIncompleteError, match="from the goal"):
            await move
    await robot.move_named("home")


async def test_io_and_mregisters(robot: RobotClient) -> None:
    await robot.write_io_bit(10010, 1)
    assert await robot.read_io_bit(10010) == 1
    await robot.write_io_bit(10010, 0)
    assert await robot.read_io_bit(10010) == 0
    await robot.write_io_group(1001, 0x5A)
    assert await robot.read_io_group(1001) == 0x5A
    await robot.write_mregister(12, 4321)
    assert await robot.read_mregister(12) == 4321
    with pytest.raises(IoError) as info:
        await robot.write_io_bit(20010, 1, check=False)
    assert info.value.result_code == IoResultCode.WRITE_ADDRESS_INVALID


async def test_tool_dh_ping(robot: RobotClient) -> None:
    await robot.select_tool(3)
    dh = await robot.get_dh_parameters()
    assert dh[0][0].d == pytest.approx(0.275, abs=1e-6)
    assert await robot.ping() < 1.0


def test_blocking_facade(sim: Sim) -> None:
    with SyncRobotClient(**sim.client_options()) as robot:
        robot.wait_for_state()
        robot.enable()
        result = robot.move_joints([0.0, 0.0, 0.0, 0.0, -1.57, 0.0])
        assert abs(result.final_positions[4] + 1.57) < TOLERANCE
        robot.write_io_bit(10020, 1)
        assert robot.read_io_bit(10020) == 1
        states = robot.states()
        assert next(states).count > 0
        states.close()
        robot.move_named("home")


async def test_connection_lost_mid_motion() -> None:
    with running_sim() as own:
        async with RobotClient(**own.client_options()) as robot:
            await robot.wait_for_state()
            await robot.enable()
            move = asyncio.create_task(
                robot.move_joints((0.8, 0.0, 0.0, 0.0, 0.0, 0.0), speed_scale=0.3)
            )
            await robot.wait_until(lambda s: bool(s.status and s.status.in_motion), 5.0, "motion")
            own.kill()
            async with asyncio.timeout(3):
                with pytest.raises(ConnectionLostError):
                    await move


async def test_several_groups_move_together_with_full_ex() -> None:
    with running_sim("--robot", "sda10f") as own:
        async with RobotClient(**own.client_options(), robot="sda10f") as robot:
            await robot.wait_for_state()
            await robot.enable()
            arm = (0.3, 0.2, 0.0, 0.1, 0.0, 0.0, 0.0)
            result = await robot.move_joints({0: arm, 1: arm, 2: (0.5,), 3: (-0.2,)})
            assert result.groups == (0, 1, 2, 3)
            assert _off((*arm, *arm, 0.5, -0.2), result.final_positions) < TOLERANCE
            result = await robot.move_joints((0.0,) * 7, group=1)  # one group: type 14
            assert _off((0.0,) * 7, result.final_positions) < TOLERANCE


async def test_safety_speed_limit_is_noticed_and_the_move_still_ends(tmp_path: Path) -> None:
    cell = tmp_path / "fsu.toml"
    cell.write_text(
        '[controller]\nmodel = "yrc1000"\nfsu_speed_limit_pct = 40\n[robot]\nmodel = "hc10"\n'
    )
    with running_sim("--config", str(cell)) as own:
        async with RobotClient(**own.client_options()) as robot:
            await robot.wait_for_state()
            await robot.enable()
            goal = (1.0, 0.0, 0.0, 0.0, -1.0, 0.0)
            result = await robot.move_joints(goal)
            assert _off(goal, result.final_positions) < TOLERANCE
            assert result.following.slowed
            assert result.following.max_lag_s > 0.25
            assert result.elapsed_s > 1.5 * result.trajectory.duration


async def test_fs100_is_big_endian_and_the_wrong_order_is_explained() -> None:
    with running_sim("--controller", "fs100", "--robot", "mh5") as own:
        async with RobotClient(**own.client_options(), controller="fs100", robot="mh5") as robot:
            await robot.wait_for_state()
            await robot.enable()
            goal = (0.3, 0.2, 0.1, 0.0, -1.0, 0.5)
            result = await robot.move_joints(goal)
            assert _off(goal, result.final_positions) < TOLERANCE
        wrong = RobotClient(**own.client_options(), controller="yrc1000", robot="mh5")
        async with wrong:
            with pytest.raises(ConnectionLostError, match=r"other byte order.*--controller"):
                await wrong.wait_for_state(5.0)
