"""RobotClient against the in-memory twin: commands, state, refusals, streaming, failures."""

from __future__ import annotations

import asyncio
import math
import socket

import pytest

from pymotoros.client import (
    BusyTimeoutError,
    CommandFailedError,
    ConnectError,
    ConnectionLostError,
    IoAddressError,
    IoError,
    NotReadyError,
    RobotClient,
    SpeedLimitError,
    StartPositionError,
)
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.state import Mode
from pymotoros.controller import cell_from_dict
from pymotoros.protocol.constants import (
    InvalidSubcode,
    IoResultCode,
    MotionCommand,
    NotReadySubcode,
    Port,
)
from pymotoros.protocol.messages import MotoJointTrajPtFullEx
from pymotoros.testing import Twin, twin

GOAL = (0.3, -0.2, 0.4, 0.1, -1.57, 0.2)
TOLERANCE = 1e-3


def _off(goal: tuple[float, ...], actual: tuple[float, ...]) -> float:
    return max(abs(a - b) for a, b in zip(goal, actual, strict=True))


async def _moving(client: RobotClient) -> None:
    await client.wait_until(lambda s: bool(s.status and s.status.in_motion), 5.0, "motion")


async def test_state_arrives_and_is_typed(client: RobotClient) -> None:
    status = client.status
    assert status is not None
    assert status.mode is Mode.PLAY
    assert status.in_motion is False
    fb = client.feedback(0)
    assert fb is not None
    assert len(fb.positions) == 6


async def test_states_iterator_and_listener(client: RobotClient) -> None:
    seen: list[int] = []
    remove = client.add_listener(lambda s: seen.append(s.count))
    counts = []
    async for state in client.states():
        counts.append(state.count)
        if len(counts) == 3:
            break
    remove()
    assert counts == sorted(counts)
    assert seen


async def test_check_motion_ready_gives_reason_with_meaning(client: RobotClient) -> None:
    readiness = await client.check_motion_ready()  # at boot: servo power off
    assert not readiness.ready
    assert readiness.reason is NotReadySubcode.SERVO_OFF
    assert "servo" in readiness.meaning
    assert "enable" in readiness.remedy
    await client.enable()
    assert (await client.check_motion_ready()).ready
    await client.disable()
    await client.wait_until(
        lambda s: s.status is not None and not s.status.motion_possible, 5.0, "INIT_ROS ended"
    )
    readiness = await client.check_motion_ready()
    assert readiness.reason is NotReadySubcode.NOT_STARTED
    assert "INIT_ROS" in readiness.meaning


@pytest.mark.parametrize("reason", [NotReadySubcode.ESTOP, NotReadySubcode.HOLD])
async def test_enable_refused_raises_not_ready(
    client: RobotClient, cell: Twin, reason: NotReadySubcode
) -> None:
    await client.enable()  # servo power on: the operator's action is the only reason left
    seen = client.state.status_count
    if reason is NotReadySubcode.ESTOP:
        cell.controller.press_estop(True)
    else:
        cell.controller.set_hold(True)
    await client.wait_until(
        lambda s: s.status_count > seen and s.status is not None and not s.status.motion_possible,
        5.0,
        "a fresh status saying motion is impossible",
    )
    with pytest.raises(NotReadyError) as info:
        await client.enable()
    err = info.value
    assert err.reason is reason
    assert str(int(reason)) in str(err)
    assert err.remedy
    assert err.remedy in str(err)
    assert err.command == MotionCommand.START_TRAJ_MODE


async def test_queue_count_and_bad_group(client: RobotClient) -> None:
    assert await client.queue_count(0) == 0
    with pytest.raises(CommandFailedError):
        await client.queue_count(3)


async def test_tool_dh_ping(client: RobotClient) -> None:
    await client.select_tool(5)
    with pytest.raises(ValueError, match=r"0\.\.63"):
        await client.select_tool(64)
    dh = await client.get_dh_parameters()
    assert len(dh) == 1
    assert dh[0][0].d == pytest.approx(0.275, abs=1e-6)
    assert await client.ping() >= 0.0


async def test_move_joints_reaches_goal_and_back_to_back(client: RobotClient) -> None:
    await client.enable()
    for goal in (GOAL, (0.0,) * 6, GOAL):
        result = await client.move_joints(goal, speed_scale=1.0)
        assert _off(goal, result.final_positions) < TOLERANCE
        assert result.stream.points == len(result.trajectory.points)
    assert result.following.samples > 0
    assert not result.following.slowed


async def test_move_named_home(client: RobotClient) -> None:
    await client.enable()
    await client.move_joints(GOAL)
    result = await client.move_named("home")
    assert max(abs(x) for x in result.final_positions) < TOLERANCE


async def test_moves_take_virtual_time_not_wall_time(client: RobotClient, cell: Twin) -> None:
    await client.enable()
    before = cell.clock.now()
    result = await client.move_joints(GOAL, speed_scale=0.5)
    assert cell.clock.now() - before >= result.trajectory.duration
    assert result.elapsed_s >= result.trajectory.duration  # measured on the client's clock


async def test_start_position_refusal_carries_deviation(client: RobotClient) -> None:
    await client.enable()
    here = await client.current_positions()
    far = list(here)
    far[4] += 0.01
    traj = JointTrajectory(
        (
            TrajectoryPoint(0.0, tuple(far), (0.0,) * 6),
            TrajectoryPoint(1.0, tuple(far), (0.0,) * 6),
        ),
        1.0,
    )
    with pytest.raises(StartPositionError) as info:
        await client.execute(traj)
    err = info.value
    assert err.subcode == InvalidSubcode.DATA_START_POS
    assert err.point == 0
    (dev,) = err.deviations
    assert dev.name == "joint_5_b"
    ppr = client.robot.groups[0].axes[4].pulses_per_unit
    assert dev.pulses is not None
    assert abs(dev.pulses - math.trunc(0.01 * ppr)) <= 1
    assert dev.difference == pytest.approx(0.01, abs=1e-4)
    assert "tolerance 30" in str(err)


async def test_speed_refusal_by_controller_and_preflight(client: RobotClient) -> None:
    await client.enable()
    start = await client.current_positions()
    fast = (0.0, 0.0, 0.0, 0.0, 0.0, 9.0)
    traj = JointTrajectory(
        (TrajectoryPoint(0.0, start, (0.0,) * 6), TrajectoryPoint(0.5, start, fast)), 0.5
    )
    with pytest.raises(SpeedLimitError) as info:
        await client.execute(traj, check_speed=False)
    assert info.value.point == 1
    assert info.value.deviations[0].name == "joint_6_t"
    await client.stop_motion()
    with pytest.raises(SpeedLimitError, match="checked before sending"):
        await client.execute(traj)


async def _sparse_plan(client: RobotClient) -> JointTrajectory:
    """Points 1 s apart: a segment of 250 increments, more than the 200-entry queue
    (0.8 s, §5.1), so MotoROS keeps the pending slot until the queue has room for the
    segment's last increments, and the next point meets BUSY (on the twin, points closer
    together are offered only once the slot is free: no BUSY at all)."""
    here = await client.current_positions()
    return client.plan(here, GOAL, speed_scale=0.05, sample_period=1.0)


async def test_busy_is_retried(client: RobotClient) -> None:
    await client.enable()
    result = await client.execute(await _sparse_plan(client))
    assert result.stream.busy_replies > 0
    assert _off(GOAL, result.final_positions) < TOLERANCE


async def test_busy_storm_ends_in_busy_timeout(client: RobotClient) -> None:
    await client.enable()
    traj = await _sparse_plan(client)
    with pytest.raises(BusyTimeoutError) as info:
        await client.execute(traj, busy_timeout_s=0.002)
    assert info.value.point is not None
    assert info.value.point > 0
    assert isinstance(info.value, TimeoutError)
    await client.stop_motion()


async def test_connection_refused_names_host_and_port() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    c = RobotClient("127.0.0.1", motion_port=port, connect_timeout_s=2.0)
    with pytest.raises(ConnectError, match=f"127.0.0.1:{port}.*refused.*--motion-port"):
        await c.connect()


async def test_connection_lost_mid_motion_raises_at_once(client: RobotClient, cell: Twin) -> None:
    await client.enable()
    move = asyncio.create_task(client.move_joints(GOAL, speed_scale=0.3))
    await _moving(client)
    await cell.drop_clients()
    async with asyncio.timeout(2):
        with pytest.raises(ConnectionLostError):
            await move
    with pytest.raises(ConnectionLostError):
        await client.queue_count()


async def test_estop_mid_motion_reports_not_ready(client: RobotClient, cell: Twin) -> None:
    await client.enable()
    move = asyncio.create_task(client.move_joints(GOAL, speed_scale=0.3))
    await _moving(client)
    cell.controller.press_estop(True)
    async with asyncio.timeout(5):
        with pytest.raises(NotReadyError) as info:
            await move
    assert info.value.reason is NotReadySubcode.ESTOP
    # Refused while still streaming (a point), or noticed while waiting (the distance left).
    assert info.value.point is not None or "from the goal" in str(info.value)


async def test_stop_motion_mid_move_is_reported(client: RobotClient) -> None:
    await client.enable()
    move = asyncio.create_task(client.move_joints((0.5, 0.0, 0.0, 0.0, 0.0, 0.0), speed_scale=0.3))
    await _moving(client)
    await client.stop_motion()
    with pytest.raises(Exception, match="from the goal") as info:
        await move
    assert type(info.value).__name__ == "MotionIncompleteError"


async def test_queue_count_while_moving_then_zero(client: RobotClient) -> None:
    await client.enable()
    move = asyncio.create_task(client.move_joints((0.4, 0.0, 0.0, 0.0, 0.0, 0.0), speed_scale=0.5))
    await _moving(client)
    moving_count = await client.queue_count()
    await move
    assert moving_count > 0
    assert await client.queue_count() == 0


async def test_slowed_robot_is_reported() -> None:
    cell = cell_from_dict(
        {"controller": {"model": "yrc1000", "fsu_speed_limit_pct": 40}, "robot": {"model": "hc10"}}
    )
    async with twin(cell=cell) as (client, _):
        await client.enable()
        samples = []
        goal = (1.0, 0.0, 0.0, 0.0, -1.0, 0.0)
        result = await client.move_joints(goal, on_progress=samples.append)
        assert _off(goal, result.final_positions) < TOLERANCE
        assert result.following.slowed
        assert result.following.max_lag_s > 0.25
        assert result.elapsed_s > 1.5 * result.trajectory.duration
        assert samples[-1].progress == pytest.approx(1.0, abs=1e-3)


async def test_io_round_trips(client: RobotClient) -> None:
    await client.write_io_bit(10010, 1)
    assert await client.read_io_bit(10010) == 1
    await client.write_io_group(1002, 0xA5)
    assert await client.read_io_group(1002) == 0xA5
    await client.write_mregister(10, 1234)
    assert await client.read_mregister(10) == 1234


async def test_io_addresses_checked_before_sending(client: RobotClient, cell: Twin) -> None:
    sent = cell.io.requests + cell.motion.requests
    with pytest.raises(IoAddressError, match="last digit"):
        await client.read_io_bit(10018)
    with pytest.raises(IoAddressError, match=r"does not write.*general output 10010-15127"):
        await client.write_io_bit(20010, 1)
    with pytest.raises(IoAddressError, match="0 or 1"):
        await client.write_io_bit(10010, 2)
    with pytest.raises(IoAddressError, match="M000-M559"):
        await client.write_mregister(560, 1)
    with pytest.raises(IoAddressError, match="1001 = 10010"):
        await client.write_io_group(2001, 1)
    assert cell.io.requests + cell.motion.requests == sent


async def test_io_refusal_from_controller(client: RobotClient) -> None:
    with pytest.raises(IoError) as info:
        await client.write_io_bit(20010, 1, check=False)
    assert info.value.result_code == IoResultCode.WRITE_ADDRESS_INVALID
    assert "1002" in str(info.value) or str(int(IoResultCode.WRITE_ADDRESS_INVALID)) in str(
        info.value
    )


async def test_mregister_needs_io_port(cell: Twin) -> None:
    c = cell.client()
    await c.connect(io=False, state=False)
    try:
        with pytest.raises(Exception, match="io port is not connected"):
            await c.read_mregister(1)
        await c.write_io_bit(10011, 1)  # bits go over the motion port
        assert await c.read_io_bit(10011) == 1
    finally:
        await c.close()


async def test_two_groups_use_full_ex() -> None:
    from pymotoros.client.point_messages import build_message

    point = TrajectoryPoint(0.5, (0.1, 0.2, 0.3), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    msg = build_message(point, 3, (0, 1), (2, 1))
    assert isinstance(msg, MotoJointTrajPtFullEx)
    assert msg.sequence == 3
    assert [r.group_no for r in msg.groups] == [0, 1]
    assert msg.groups[1].pos[0] == pytest.approx(0.3)
    assert msg.groups[0].valid_fields == 15


async def test_several_groups_move_together_with_full_ex() -> None:
    async with twin(robot="sda10f") as (robot, _):
        await robot.enable()
        arm = (0.3, 0.2, 0.0, 0.1, 0.0, 0.0, 0.0)
        result = await robot.move_joints({0: arm, 1: arm, 2: (0.5,), 3: (-0.2,)})
        assert result.groups == (0, 1, 2, 3)
        assert _off((*arm, *arm, 0.5, -0.2), result.final_positions) < TOLERANCE
        result = await robot.move_joints((0.0,) * 7, group=1)  # one group: type 14
        assert _off((0.0,) * 7, result.final_positions) < TOLERANCE


async def test_fs100_is_big_endian_and_the_wrong_order_is_explained() -> None:
    async with twin(robot="mh5", controller="fs100") as (robot, the_twin):
        await robot.enable()
        goal = (0.3, 0.2, 0.1, 0.0, -1.0, 0.5)
        result = await robot.move_joints(goal)
        assert _off(goal, result.final_positions) < TOLERANCE
        # the motion port's first reply (to the STOP_MOTION every connect sends) already
        # reads well only in the other byte order
        with pytest.raises(ConnectionLostError, match=r"other byte order.*--controller"):
            async with the_twin.client(controller="yrc1000") as wrong:
                await wrong.wait_for_state(5.0)


async def test_not_connected_port_is_a_clear_error() -> None:
    c = RobotClient("127.0.0.1")  # never connected
    with pytest.raises(Exception, match="motion port is not connected"):
        await c.queue_count()


async def test_close_is_idempotent(cell: Twin) -> None:
    c = cell.client()
    await c.connect()
    await c.close()
    await c.close()
    assert c.ports.of(Port.MOTION) == 50240
