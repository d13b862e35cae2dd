"""A raw Simple Message peer over asyncio streams, built on the codec only (no client)."""

from __future__ import annotations

import asyncio
import contextlib

from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port, ResultCode
from pymotoros.protocol.framing import Frame, FrameDecoder, decode_reply, encode
from pymotoros.protocol.messages import (
    JointTrajPtFull,
    MotoMotionCtrl,
    MotoMotionReply,
    WireMessage,
)

TIMEOUT = 5.0


class Peer:
    def __init__(
        self,
        reader: asyncio.StreamReader,
        writer: asyncio.StreamWriter,
        port: Port,
        order: ByteOrder,
    ) -> None:
        self.reader = reader
        self.writer = writer
        self.port = port
        self.order = order
        self.decoder = FrameDecoder(order)

    @classmethod
    async def connect(cls, tcp_port: int, port: Port, order: ByteOrder = ByteOrder.LITTLE) -> Peer:
        async with asyncio.timeout(TIMEOUT):
            reader, writer = await asyncio.open_connection("127.0.0.1", tcp_port)
        return cls(reader, writer, port, order)

    async def send(self, message: WireMessage, **header: int) -> None:
        self.writer.write(encode(message, self.order, **header))
        await self.writer.drain()

    async def send_raw(self, data: bytes) -> None:
        self.writer.write(data)
        await self.writer.drain()

    async def frame(self) -> Frame:
        async with asyncio.timeout(TIMEOUT):
            while (frame := self.decoder.next_frame()) is None:
                data = await self.reader.read(4096)
                if not data:
                    raise ConnectionError("server closed the connection")
                self.decoder.feed(data)
        return frame

    async def message(self) -> WireMessage:
        return decode_reply(await self.frame(), self.order, self.port)

    async def request(self, message: WireMessage, **header: int) -> WireMessage:
        await self.send(message, **header)
        return await self.message()

    async def is_closed_by_server(self) -> bool:
        """True if the server closes without sending anything more."""
        async with asyncio.timeout(TIMEOUT):
            data = await self.reader.read(4096)
        return data == b""

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(ConnectionError):
            await self.writer.wait_closed()


def header(frame: Frame) -> tuple[int, int, int]:
    """The (message type, communication type, reply type) of ``frame``'s header."""
    return frame.msg_type, frame.comm_type, frame.reply_type


async def ctrl(peer: Peer, command: int, group: int = 0, sequence: int = 0) -> tuple[int, int]:
    """Send a MOTO_MOTION_CTRL; (result, subcode) of the reply, whose echo is checked."""
    reply = await peer.request(MotoMotionCtrl(group, sequence, command))
    assert isinstance(reply, MotoMotionReply)
    assert (reply.group_no, reply.sequence, reply.command) == (group, sequence, command)
    return reply.result, reply.subcode


async def start_a_far_move(peer: Peer) -> JointTrajPtFull:
    """START_TRAJ_MODE and the start point (all joints at 0), both accepted; returns the
    point to send next: joint 1 to 0.5 rad 14,399 s later (legal, and extreme: issue 13)."""
    ok = ResultCode.SUCCESS
    assert await ctrl(peer, MotionCommand.START_TRAJ_MODE) == (ok, 0)
    start = JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6)
    assert await peer.request(start) == MotoMotionReply(0, 0, 14, ok, 0)
    return JointTrajPtFull.for_joints(0, 1, 14399.0, [0.5] + [0.0] * 5, [0.0] * 6)
