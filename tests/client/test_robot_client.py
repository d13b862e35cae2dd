"""RobotClient against the fake peer: commands, state, refusals, streaming, failures."""

from __future__ import annotations

import asyncio
import math
import socket

import pytest
from client_peer import ClientPeer, client_for

from pymotoros.client import (
    BusyTimeoutError,
    CommandFailedError,
    ConnectError,
    ConnectionLostError,
    IoAddressError,
    IoError,
    NotReadyError,
    RequestTimeoutError,
    RobotClient,
    SpeedLimitError,
    StartPositionError,
)
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.state import Mode
from pymotoros.protocol.constants import (
    InvalidSubcode,
    IoResultCode,
    MotionCommand,
    NotReadySubcode,
    Port,
)
from pymotoros.protocol.messages import MotoJointTrajPtFullEx

GOAL = (0.3, -0.2, 0.4, 0.1, -1.57, 0.2)


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
    readiness = await client.check_motion_ready()
    assert not readiness.ready
    assert readiness.reason is NotReadySubcode.NOT_STARTED
    assert "INIT_ROS" in readiness.meaning
    assert "enable" in readiness.remedy
    await client.enable()
    assert (await client.check_motion_ready()).ready


@pytest.mark.parametrize("reason", [NotReadySubcode.ESTOP, NotReadySubcode.HOLD])
async def test_enable_refused_raises_not_ready(
    peer: ClientPeer, client: RobotClient, reason: NotReadySubcode
) -> None:
    peer.enable_refusal = reason
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


async def test_tool_dh_ping(peer: ClientPeer, client: RobotClient) -> None:
    await client.select_tool(5)
    assert peer.tool == 5
    with pytest.raises(ValueError, match=r"0\.\.63"):
        await client.select_tool(64)
    dh = await client.get_dh_parameters()
    assert len(dh) == 1
    assert dh[0][0].d == pytest.approx(0.1)
    assert await client.ping() >= 0.0


async def test_move_joints_reaches_goal_and_back_to_back(client: RobotClient) -> None:
    await client.enable()
    for goal in (GOAL, (0.0,) * 6, GOAL):
        result = await client.move_joints(goal, speed_scale=1.0)
        assert max(abs(a - b) for a, b in zip(result.final_positions, goal, strict=True)) < 1e-3
        assert result.stream.points == len(result.trajectory.points)
    assert result.following.samples > 0


async def test_move_named_home(client: RobotClient) -> None:
    await client.enable()
    await client.move_joints(GOAL)
    result = await client.move_named("home")
    assert max(abs(x) for x in result.final_positions) < 1e-3


async def test_start_position_refusal_carries_deviation(client: RobotClient) -> None:
    await client.enable()
    far = (0.0, 0.0, 0.0, 0.0, 0.01, 0.0)
    traj = JointTrajectory(
        (TrajectoryPoint(0.0, far, (0.0,) * 6), TrajectoryPoint(1.0, far, (0.0,) * 6)), 1.0
    )
    with pytest.raises(StartPositionError) as info:
        await client.execute(traj)
    err = info.value
    assert err.subcode == InvalidSubcode.DATA_START_POS
    assert err.point == 0
    (dev,) = err.deviations
    assert dev.name == "joint_5_b"
    ppr = client.robot.groups[0].axes[4].pulses_per_unit
    assert dev.pulses == math.trunc(0.01 * ppr)
    assert dev.difference == pytest.approx(0.01)
    assert "tolerance 30" in str(err)


async def test_speed_refusal_by_controller_and_preflight(client: RobotClient) -> None:
    await client.enable()
    start = client.state.positions(0)
    assert start is not None
    fast = (0.0, 0.0, 0.0, 0.0, 9.0, 0.0)
    traj = JointTrajectory(
        (TrajectoryPoint(0.0, start, (0.0,) * 6), TrajectoryPoint(0.5, start, fast)), 0.5
    )
    with pytest.raises(SpeedLimitError) as info:
        await client.execute(traj, check_speed=False)
    assert info.value.point == 1
    assert info.value.deviations[0].name == "joint_5_b"
    with pytest.raises(SpeedLimitError, match="checked before sending"):
        await client.execute(traj)


async def test_busy_is_retried(peer: ClientPeer, client: RobotClient) -> None:
    await client.enable()
    peer.busy_per_point = 2
    result = await client.move_joints(GOAL)
    assert result.stream.busy_replies >= 2 * (len(result.trajectory.points) - 2)


async def test_busy_storm_ends_in_busy_timeout(peer: ClientPeer, client: RobotClient) -> None:
    await client.enable()
    peer.busy_forever = True
    async with asyncio.timeout(10):
        with pytest.raises(BusyTimeoutError) as info:
            await client.move_joints(GOAL, busy_timeout_s=0.2)
    assert info.value.point == 1
    assert isinstance(info.value, TimeoutError)


async def test_connection_refused_names_host_and_port() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    c = RobotClient("127.0.0.1", motion_port=port, connect_timeout_s=2.0)
    with pytest.raises(ConnectError, match=f"127.0.0.1:{port}.*refused.*--motion-port"):
        await c.connect()


async def test_connection_lost_mid_motion_raises_at_once(
    peer: ClientPeer, client: RobotClient
) -> None:
    await client.enable()
    move = asyncio.create_task(client.move_joints(GOAL, speed_scale=0.3))
    await client.wait_until(lambda s: bool(s.status and s.status.in_motion), 5.0, "motion")
    await peer.drop_clients()
    async with asyncio.timeout(2):
        with pytest.raises(ConnectionLostError):
            await move
    with pytest.raises(ConnectionLostError):
        await client.queue_count()


async def test_stop_mid_motion_reports_not_ready(peer: ClientPeer, client: RobotClient) -> None:
    await client.enable()
    move = asyncio.create_task(client.move_joints(GOAL, speed_scale=0.3))
    await client.wait_until(lambda s: bool(s.status and s.status.in_motion), 5.0, "motion")
    peer.stop()
    peer.ready = False
    peer.not_ready = NotReadySubcode.ESTOP
    async with asyncio.timeout(5):
        with pytest.raises(NotReadyError) as info:
            await move
    assert info.value.reason is NotReadySubcode.ESTOP
    # Refused while still streaming (a point), or noticed while waiting (the distance left).
    assert info.value.point is not None or "from the goal" in str(info.value)


async def test_slowed_robot_is_reported(peer: ClientPeer, client: RobotClient) -> None:
    await client.enable()
    peer.speed_scale = 0.5
    samples = []
    result = await client.move_joints((0.0, 0.0, 0.0, 0.0, -1.5, 0.0), on_progress=samples.append)
    assert result.following.slowed
    assert result.following.max_lag_s > 0.25
    assert samples[-1].progress == pytest.approx(1.0, abs=1e-3)


async def test_request_timeout(peer: ClientPeer, client: RobotClient) -> None:
    peer.silent.add(MotionCommand.CHECK_QUEUE_CNT)
    c = client
    c.timeout_s = 0.2
    with pytest.raises(RequestTimeoutError, match=r"within 0\.2 s"):
        await c.queue_count()
    peer.silent.clear()
    assert await c.queue_count() == 0


async def test_reply_with_wrong_echo_is_not_taken(peer: ClientPeer, client: RobotClient) -> None:
    peer.wrong_echo = True
    readiness = await client.check_motion_ready()
    assert readiness.reason is NotReadySubcode.NOT_STARTED


async def test_io_round_trips(peer: ClientPeer, client: RobotClient) -> None:
    await client.write_io_bit(10010, 1)
    assert await client.read_io_bit(10010) == 1
    await client.write_io_group(1002, 0xA5)
    assert await client.read_io_group(1002) == 0xA5
    await client.write_mregister(10, 1234)
    assert await client.read_mregister(10) == 1234
    assert peer.mreg[10] == 1234


async def test_io_addresses_checked_before_sending(peer: ClientPeer, client: RobotClient) -> None:
    sent = len(peer.received)
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
    assert len(peer.received) == sent


async def test_io_refusal_from_controller(client: RobotClient) -> None:
    with pytest.raises(IoError) as info:
        await client.write_io_bit(10010, 2, check=False)
    assert info.value.result_code == IoResultCode.WRITE_VALUE_INVALID
    assert "1003" in str(info.value)


async def test_mregister_needs_io_port(peer: ClientPeer) -> None:
    async with client_for(peer) as c:
        await c.close()
    c = client_for(peer)
    await c.connect(io=False, state=False)
    try:
        with pytest.raises(Exception, match="io port is not connected"):
            await c.read_mregister(1)
        await c.write_io_bit(10011, 1)  # bits go over the motion port
        assert peer.io[10011] == 1
    finally:
        await c.close()


async def test_two_groups_use_full_ex() -> None:
    from pymotoros.client.streaming import build_message

    point = TrajectoryPoint(0.5, (0.1, 0.2, 0.3), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    msg = build_message(point, 3, (0, 1), (2, 1))
    assert isinstance(msg, MotoJointTrajPtFullEx)
    assert msg.sequence == 3
    assert [r.group_no for r in msg.groups] == [0, 1]
    assert msg.groups[1].pos[0] == pytest.approx(0.3)
    assert msg.groups[0].valid_fields == 15


async def test_not_connected_port_is_a_clear_error() -> None:
    c = RobotClient(port_check := "127.0.0.1")  # noqa: F841 - never connected
    with pytest.raises(Exception, match="motion port is not connected"):
        await c.queue_count()


async def test_close_is_idempotent(peer: ClientPeer) -> None:
    c = client_for(peer)
    await c.connect()
    await c.close()
    await c.close()
    assert Port.MOTION in peer.ports
