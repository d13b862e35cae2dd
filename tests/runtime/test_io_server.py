"""IO port (50242): M-registers, result codes in reply bodies, the IO error reply (§1.6, §6.1)."""

from __future__ import annotations

import struct

from pymotoros.controller import VirtualController
from pymotoros.protocol.constants import ByteOrder, CommType, MsgType, Port, ReplyType
from pymotoros.protocol.framing import Frame, encode_frame
from pymotoros.protocol.messages import (
    IoErrorReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
    MotoReadMRegister,
    MotoReadMRegisterReply,
    MotoWriteIoBit,
    MotoWriteIoBitReply,
    MotoWriteMRegister,
    MotoWriteMRegisterReply,
    Ping,
    UnknownMessage,
)
from pymotoros.runtime.app import SimulatorApp

from .peer import Peer, header


async def io_peer(app: SimulatorApp) -> Peer:
    return await Peer.connect(app.ports.io, Port.IO)


async def test_io_error_reply_layout_for_unknown_type(app: SimulatorApp) -> None:
    peer = await io_peer(app)
    await peer.send(Ping())
    frame = await peer.frame()
    assert header(frame) == (MsgType.MOTO_MOTION_REPLY, CommType.SERVICE_REPLY, ReplyType.SUCCESS)
    assert len(frame.body) == 60
    assert struct.unpack_from("<ii", frame.body) == (3, 3003)
    assert frame.body[8:] == bytes(52)
    assert await peer.request(UnknownMessage(2001, bytes(52))) == IoErrorReply(3, 3003)
    await peer.close()


async def test_io_error_reply_for_short_message_keeps_connection(app: SimulatorApp) -> None:
    peer = await io_peer(app)
    await peer.send_raw(
        encode_frame(Frame(MsgType.MOTO_WRITE_MREGISTER, 2, 0, b"\1\0\0\0"), ByteOrder.LITTLE)
    )
    assert await peer.message() == IoErrorReply(3, 3001)
    assert await peer.request(MotoReadIoBit(10010)) == MotoReadIoBitReply(0, 0)
    await peer.close()


async def test_m_registers_and_result_codes(
    app: SimulatorApp, controller: VirtualController
) -> None:
    peer = await io_peer(app)
    assert await peer.request(MotoWriteMRegister(12, 0xBEEF)) == MotoWriteMRegisterReply(0)
    assert await peer.request(MotoReadMRegister(12)) == MotoReadMRegisterReply(0xBEEF, 0)
    assert await peer.request(MotoWriteMRegister(12, 0x10000)) == MotoWriteMRegisterReply(1003)
    assert await peer.request(MotoWriteIoBit(10, 1)) == MotoWriteIoBitReply(1002)
    await peer.send(MotoReadIoBit(10018))
    frame = await peer.frame()
    assert frame.reply_type == ReplyType.FAILURE  # IO failures say so in the header (§1.2)
    assert struct.unpack("<II", frame.body) == (0, 1001)
    # a reply is sent whatever the comm_type
    reply = await peer.request(MotoReadMRegister(12), comm_type=CommType.SERVICE_REPLY)
    assert reply == MotoReadMRegisterReply(0xBEEF, 0)
    assert controller.read_io_bit(11126).value == 1  # OT#895: an IO client has connected
    controller.set_io_api_failure(reads=True, writes=True)
    assert await peer.request(MotoReadMRegister(12)) == MotoReadMRegisterReply(0, 1004)
    assert await peer.request(MotoWriteIoBit(10010, 1)) == MotoWriteIoBitReply(1005)
    await peer.close()


async def test_second_io_client_replaces_the_first(app: SimulatorApp) -> None:
    first = await io_peer(app)
    assert await first.request(MotoReadIoBit(10010)) == MotoReadIoBitReply(0, 0)
    second = await io_peer(app)
    assert await first.is_closed_by_server()
    assert await second.request(MotoReadIoBit(10010)) == MotoReadIoBitReply(0, 0)
    await first.close()
    await second.close()
