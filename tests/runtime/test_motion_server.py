"""Motion port edge cases (reference §1.5, §2.2, §3.1, §5.9) against a stand-in controller."""

from __future__ import annotations

import asyncio
import logging
import struct

import pytest
from fake_controller import FakeController
from peer import Peer

from pymotoros.protocol.constants import (
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
    MotoGetDhParameters,
    MotoGetDhParametersReply,
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

LE = "<"


async def motion_peer(app: SimulatorApp) -> Peer:
    return await Peer.connect(app.ports.motion, Port.MOTION)


def ctrl(command: int, group: int = 0, sequence: int = 0) -> MotoMotionCtrl:
    return MotoMotionCtrl(group, sequence, command)


async def wait_event(fake: FakeController, event: str) -> None:
    async with asyncio.timeout(5.0):
        await fake.wait_event(event)


async def test_ping_and_single_write_replies(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    await peer.send(Ping())
    frame = await peer.frame()
    assert (frame.msg_type, frame.comm_type, frame.reply_type) == (
        MsgType.PING,
        CommType.SERVICE_REPLY,
        ReplyType.SUCCESS,
    )
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
    ],
    ids=["13", "15", "2002"],
)
async def test_state_and_reply_types_close_the_motion_connection(
    app: SimulatorApp, fake: FakeController, message: object
) -> None:
    peer = await motion_peer(app)
    await peer.send(message)  # type: ignore[arg-type]
    assert await peer.is_closed_by_server()
    await wait_event(fake, "motion_disconnected")
    await peer.close()


async def test_disconnect_closes_without_reply(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    await peer.send(ctrl(MotionCommand.DISCONNECT))
    assert await peer.is_closed_by_server()
    await peer.close()


async def test_dh_failure_closes_and_success_replies(
    app: SimulatorApp, fake: FakeController
) -> None:
    peer = await motion_peer(app)
    reply = await peer.request(MotoGetDhParameters())
    assert isinstance(reply, MotoGetDhParametersReply)
    assert reply.groups[0][0].d == pytest.approx(0.275)
    fake.dh_ok = False
    await peer.send(MotoGetDhParameters())
    assert await peer.is_closed_by_server()
    await peer.close()


async def test_pending_request_completes_in_a_later_tick(
    app: SimulatorApp, fake: FakeController
) -> None:
    peer = await motion_peer(app)
    before = fake.ticks
    reply = await peer.request(ctrl(MotionCommand.START_TRAJ_MODE, sequence=7))
    assert reply == MotoMotionReply(0, 7, MotionCommand.START_TRAJ_MODE, 0, 0)
    assert fake.ticks >= before + 10
    await peer.close()


async def test_refusal_is_logged_with_meaning(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    peer = await motion_peer(app)
    with caplog.at_level(logging.WARNING, logger="pymotoros.runtime.motion_server"):
        reply = await peer.request(MotoSelectTool(0, 99, 3))
    assert reply == MotoMotionReply(0, 3, 2018, ResultCode.INVALID, 3017)
    [record] = [r for r in caplog.records if "SELECT_TOOL" in r.getMessage()]
    assert "3017" in record.getMessage()
    assert "tool 99 outside 0..63" in record.getMessage()
    await peer.close()


async def test_points_and_io_on_the_motion_port(app: SimulatorApp, fake: FakeController) -> None:
    peer = await motion_peer(app)
    point = JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6)
    assert await peer.request(point) == MotoMotionReply(0, 0, 14, 0, 0)
    ex = MotoJointTrajPtFullEx.for_groups(
        5, [JointTrajPtExData.for_joints(g, 0.1, [0.0] * 6, [0.0] * 6) for g in (0, 1)]
    )
    assert await peer.request(ex) == MotoMotionReply(1, 5, 2016, 0, 0)
    assert await peer.request(MotoWriteIoGroup(1001, 0xA5)) == MotoWriteIoGroupReply(0)
    assert await peer.request(MotoReadIoBit(10010)) == MotoReadIoBitReply(1, 0)
    assert fake.events[-2:] == ["point 0", "point_ex 5 2"]
    await peer.close()


async def test_service_reply_comm_type_is_processed_without_reply(
    app: SimulatorApp, fake: FakeController
) -> None:
    peer = await motion_peer(app)
    await peer.send(ctrl(MotionCommand.STOP_MOTION), comm_type=CommType.SERVICE_REPLY)
    assert isinstance(await peer.request(Ping()), PingReply)  # the next reply is the PING's
    assert f"ctrl {MotionCommand.STOP_MOTION}" in fake.events
    await peer.close()


async def test_fragmented_and_pipelined_frames(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    peer = await motion_peer(app)
    data = encode(ctrl(MotionCommand.CHECK_QUEUE_CNT, sequence=1), LE)
    with caplog.at_level(logging.DEBUG, logger="pymotoros.runtime.motion_server"):
        for index in range(len(data)):
            peer.writer.write(data[index : index + 1])
            await peer.writer.drain()
            await asyncio.sleep(0.001)  # pacing so that the bytes arrive in separate reads
        reply = await peer.message()
    assert reply == MotoMotionReply(0, 1, MotionCommand.CHECK_QUEUE_CNT, 0, 7)
    assert any("a real controller would answer 3001" in r.getMessage() for r in caplog.records)
    # two requests in one write: two replies, in order
    await peer.send_raw(encode(Ping(), LE) + encode(ctrl(MotionCommand.CHECK_QUEUE_CNT), LE))
    assert isinstance(await peer.message(), PingReply)
    assert isinstance(await peer.message(), MotoMotionReply)
    await peer.close()


async def test_bad_length_prefix_answers_3001_and_keeps_connection(app: SimulatorApp) -> None:
    peer = await motion_peer(app)
    await peer.send_raw(struct.pack("<iiii", 100000, 2001, 2, 0))
    reply = await peer.message()
    assert isinstance(reply, MotoMotionReply)
    assert (reply.result, reply.subcode) == (ResultCode.INVALID, InvalidSubcode.MSGSIZE)
    assert isinstance(await peer.request(Ping()), PingReply)
    await peer.close()


async def test_second_client_replaces_the_first_when_nothing_is_queued(
    app: SimulatorApp, fake: FakeController
) -> None:
    first = await motion_peer(app)
    assert isinstance(await first.request(Ping()), PingReply)
    second = await motion_peer(app)
    assert await first.is_closed_by_server()
    assert isinstance(await second.request(Ping()), PingReply)
    assert app.motion.replaced == 1
    await first.close()
    await second.close()


async def test_second_client_is_refused_while_motion_is_queued(
    app: SimulatorApp, fake: FakeController
) -> None:
    first = await motion_peer(app)
    assert isinstance(await first.request(Ping()), PingReply)
    fake.queued = True
    second = await motion_peer(app)
    assert await second.is_closed_by_server()
    assert isinstance(await first.request(Ping()), PingReply)
    assert app.motion.refused == 1
    await first.close()
    await second.close()


async def test_dropping_the_motion_connection_clears_the_queues(
    app: SimulatorApp, fake: FakeController
) -> None:
    peer = await motion_peer(app)
    assert isinstance(await peer.request(Ping()), PingReply)
    assert fake.events[0] == "motion_connected"
    await peer.close()
    await wait_event(fake, "motion_disconnected")
