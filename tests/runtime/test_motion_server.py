"""Motion port edge cases (reference §1.5, §2.2, §3.1, §5.9) against the virtual controller."""

from __future__ import annotations

import asyncio
import logging
import struct

import pytest

from pymotoros.controller import VirtualController
from pymotoros.protocol.constants import (
    ByteOrder,
    CommType,
    InvalidSubcode,
    MotionCommand,
    MsgType,
    Port,
    ReplyType,
    ResultCode,
)
from pymotoros.protocol.framing import Frame, encode, encode_frame
from pymotoros.protocol.messages import (
    JointFeedback,
    JointTrajPtExData,
    JointTrajPtFull,
    Message,
    MotoGetDhParameters,
    MotoGetDhParametersReply,
    MotoJointFeedbackEx,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
    MotoReadMRegister,
    MotoSelectTool,
    MotoWriteIoGroup,
    MotoWriteIoGroupReply,
    Ping,
    PingReply,
    RobotStatus,
    UnknownMessage,
)
from pymotoros.runtime.app import SimulatorApp

from .peer import Peer, ctrl, header
from .support import until

LE = ByteOrder.LITTLE
OK = (ResultCode.SUCCESS, 0)
MOTION_SERVER_OUTPUT = 11124
"""OT#893: MotoROS turns it on while a motion connection exists (§6.3)."""


async def motion_peer(app: SimulatorApp) -> Peer:
    return await Peer.connect(app.ports.motion, Port.MOTION)


async def start_trajectory(peer: Peer, app: SimulatorApp) -> None:
    """Enable, then queue a 2 s move of joint 1 (the queue holds increments afterwards)."""
    assert await ctrl(peer, MotionCommand.START_TRAJ_MODE) == OK
    start = JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6)
    end = JointTrajPtFull.for_joints(0, 1, 2.0, [0.3] + [0.0] * 5, [0.0] * 6)
    assert await peer.request(start) == MotoMotionReply(0, 0, 14, 0, 0)
    assert await peer.request(end) == MotoMotionReply(0, 1, 14, 0, 0)
    controller = app.controller
    await until(app, "queued motion", controller.has_queued_motion)


async def test_ping_and_single_write_replies(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    await peer.send(Ping())
    frame = await peer.frame()
    assert header(frame) == (MsgType.PING, CommType.SERVICE_REPLY, ReplyType.SUCCESS)
    assert frame.body == b""
    await peer.close()


async def test_unknown_type_answers_3003_and_keeps_connection(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    for msg_type in (2, 11, 2011, 2012, 2013, 9999):  # 2012/2013: M-registers are IO-port only
        reply = await peer.request(UnknownMessage(msg_type, b"\0" * 8))
        assert reply == MotoMotionReply(
            -1, -1, msg_type, ResultCode.INVALID, InvalidSubcode.MSGTYPE
        )
    reply = await peer.request(MotoReadMRegister(5))
    assert reply == MotoMotionReply(-1, -1, 2012, ResultCode.INVALID, InvalidSubcode.MSGTYPE)
    assert isinstance(await peer.request(Ping()), PingReply)
    await peer.close()


async def test_short_message_answers_3001_with_echo(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    # MOTION_CTRL cut after group, sequence and command: group 0, sequence and command echoed
    body = struct.pack("<iii", 3, 42, MotionCommand.CHECK_QUEUE_CNT)
    await peer.send_raw(encode_frame(Frame(MsgType.MOTO_MOTION_CTRL, 2, 0, body), LE))
    reply = await peer.message()
    assert reply == MotoMotionReply(
        0, 42, MotionCommand.CHECK_QUEUE_CNT, ResultCode.INVALID, InvalidSubcode.MSGSIZE
    )
    # a short read-IO: group and sequence -1, command = the type
    await peer.send_raw(encode_frame(Frame(MsgType.MOTO_READ_IO_BIT, 2, 0, b""), LE))
    reply = await peer.message()
    assert reply == MotoMotionReply(-1, -1, 2003, ResultCode.INVALID, InvalidSubcode.MSGSIZE)
    assert isinstance(await peer.request(Ping()), PingReply)
    await peer.close()


@pytest.mark.parametrize(
    "message",
    [
        RobotStatus(0, 0, 0, 0, 0, 1, 0),
        JointFeedback.for_joints(0, [0.0] * 6, [0.0] * 6),
        MotoMotionReply(0, 0, 0, 0, 0),
        MotoJointFeedbackEx.for_groups([JointFeedback.for_joints(0, [0.0], [0.0])] * 2),
    ],
    ids=["13", "15", "2002", "2017"],
)
async def test_state_and_reply_types_close_the_motion_connection(
    app: SimulatorApp, controller: VirtualController, message: Message
) -> None:
    peer = await motion_peer(app)
    assert isinstance(await peer.request(Ping()), PingReply)
    assert controller.read_io_bit(MOTION_SERVER_OUTPUT).value == 1
    await peer.send(message)
    assert await peer.is_closed_by_server()
    await until(app, "OT#893 off", lambda: controller.read_io_bit(MOTION_SERVER_OUTPUT).value == 0)
    await peer.close()


async def test_disconnect_closes_without_reply(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    await peer.send(MotoMotionCtrl(0, 0, MotionCommand.DISCONNECT))
    assert await peer.is_closed_by_server()
    await peer.close()


async def test_dh_failure_closes_and_success_replies(
    app: SimulatorApp, controller: VirtualController, monkeypatch: pytest.MonkeyPatch
) -> None:
    peer = await motion_peer(app)
    reply = await peer.request(MotoGetDhParameters())
    assert isinstance(reply, MotoGetDhParametersReply)
    assert reply.groups[0][0].d == pytest.approx(0.275)
    assert reply.groups[1] == reply.groups[3]  # groups the cell does not have are zero
    monkeypatch.setattr(controller, "dh_parameters", lambda: None)  # the library read fails
    await peer.send(MotoGetDhParameters())
    assert await peer.is_closed_by_server()
    await peer.close()


async def test_pending_request_completes_in_a_later_tick(
    vapp: SimulatorApp, controller: VirtualController
) -> None:
    peer = await motion_peer(vapp)
    assert await ctrl(peer, MotionCommand.CHECK_MOTION_READY) == (ResultCode.FALSE, 5006)
    before = controller.tick_count
    assert await ctrl(peer, MotionCommand.START_TRAJ_MODE, sequence=7) == OK
    assert controller.tick_count > before + 10  # servo power-up and the job took ticks
    assert await ctrl(peer, MotionCommand.CHECK_MOTION_READY) == OK
    await peer.close()


async def test_refusal_is_logged_once_with_meaning(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    peer = await motion_peer(app)
    with caplog.at_level(logging.WARNING, logger="pymotoros.runtime.motion_server"):
        reply = await peer.request(MotoSelectTool(0, 99, 3))
    assert reply == MotoMotionReply(0, 3, 2018, ResultCode.INVALID, 3017)
    [record] = [r for r in caplog.records if "SELECT_TOOL" in r.getMessage()]
    assert "3017" in record.getMessage()
    assert "99" in record.getMessage()
    await peer.close()


async def test_points_and_io_on_the_motion_port(
    vapp: SimulatorApp, controller: VirtualController
) -> None:
    peer = await motion_peer(vapp)
    point = JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6)
    assert await peer.request(point) == MotoMotionReply(0, 0, 14, ResultCode.NOT_READY, 5006)
    assert await ctrl(peer, MotionCommand.START_TRAJ_MODE) == OK
    assert await peer.request(point) == MotoMotionReply(0, 0, 14, 0, 0)
    ex = MotoJointTrajPtFullEx.for_groups(
        1, [JointTrajPtExData.for_joints(0, 0.1, [0.001] + [0.0] * 5, [0.0] * 6)]
    )
    assert await peer.request(ex) == MotoMotionReply(0, 1, 2016, 0, 0)
    bad_group = MotoJointTrajPtFullEx.for_groups(
        2, [JointTrajPtExData.for_joints(3, 0.2, [0.0] * 6, [0.0] * 6)]
    )
    assert await peer.request(bad_group) == MotoMotionReply(3, 2, 2016, ResultCode.INVALID, 3004)
    assert await peer.request(MotoWriteIoGroup(1001, 0xA5)) == MotoWriteIoGroupReply(0)
    assert await peer.request(MotoReadIoBit(10010)) == MotoReadIoBitReply(1, 0)
    await peer.close()


async def test_service_reply_comm_type_is_processed_without_reply(
    app: SimulatorApp, controller: VirtualController
) -> None:
    peer = await motion_peer(app)
    await peer.send(MotoSelectTool(0, 5, 1), comm_type=CommType.SERVICE_REPLY)
    assert isinstance(await peer.request(Ping()), PingReply)  # the next reply is the PING's
    assert controller.snapshot().groups[0].tool == 5
    await peer.close()


@pytest.mark.fidelity("safe")
async def test_fragmented_and_pipelined_frames(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    """Safe: a request written a byte at a time is reassembled (exact: 3001,
    tests/runtime/test_fidelity_wire.py)."""
    peer = await motion_peer(app)
    data = encode(MotoMotionCtrl(0, 1, MotionCommand.CHECK_QUEUE_CNT), LE)
    with caplog.at_level(logging.DEBUG, logger="pymotoros.runtime.motion_server"):
        for index in range(len(data)):
            peer.writer.write(data[index : index + 1])
            await peer.writer.drain()
            await asyncio.sleep(0.001)  # pacing only: the bytes must arrive in separate reads
        reply = await peer.message()
    assert reply == MotoMotionReply(0, 1, MotionCommand.CHECK_QUEUE_CNT, 0, 0)
    assert any("a real controller would answer 3001" in r.getMessage() for r in caplog.records)
    # two requests in one write: two replies, in order
    await peer.send_raw(
        encode(Ping(), LE) + encode(MotoMotionCtrl(0, 2, MotionCommand.CHECK_QUEUE_CNT), LE)
    )
    assert isinstance(await peer.message(), PingReply)
    assert await peer.message() == MotoMotionReply(0, 2, MotionCommand.CHECK_QUEUE_CNT, 0, 0)
    await peer.close()


async def test_bad_length_prefix_answers_3001_and_keeps_connection(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    await peer.send_raw(struct.pack("<iiii", 100000, 2001, 2, 0))
    reply = await peer.message()
    assert isinstance(reply, MotoMotionReply)
    assert (reply.result, reply.subcode) == (ResultCode.INVALID, InvalidSubcode.MSGSIZE)
    assert isinstance(await peer.request(Ping()), PingReply)
    await peer.close()


async def test_second_client_replaces_the_first_when_nothing_is_queued(app: SimulatorApp) -> None:
    first = await motion_peer(app)
    assert isinstance(await first.request(Ping()), PingReply)
    second = await motion_peer(app)
    assert await first.is_closed_by_server()
    assert isinstance(await second.request(Ping()), PingReply)
    assert app.motion.replaced == 1
    await first.close()
    await second.close()


async def test_second_client_is_refused_while_motion_is_queued(
    vapp: SimulatorApp, controller: VirtualController
) -> None:
    first = await motion_peer(vapp)
    await start_trajectory(first, vapp)
    second = await motion_peer(vapp)
    assert await second.is_closed_by_server()
    assert isinstance(await first.request(Ping()), PingReply)
    assert vapp.motion.refused == 1
    # the IO port applies the same test to the motion queues (§2.2)
    io_first = await Peer.connect(vapp.ports.io, Port.IO)
    io_second = await Peer.connect(vapp.ports.io, Port.IO)
    assert await io_second.is_closed_by_server()
    for peer in (first, second, io_first, io_second):
        await peer.close()


@pytest.mark.fidelity("safe")
async def test_dropping_the_motion_connection_clears_the_queues(
    vapp: SimulatorApp, controller: VirtualController
) -> None:
    peer = await motion_peer(vapp)
    await start_trajectory(peer, vapp)
    assert controller.snapshot().groups[0].queue > 0
    await peer.close()
    await until(vapp, "queues cleared", lambda: not controller.has_queued_motion())
    assert controller.snapshot().groups[0].queue == 0
