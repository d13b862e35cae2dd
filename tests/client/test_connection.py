"""FrameConnection on its own: fragmented and coalesced replies, stale replies, failures."""

from __future__ import annotations

import asyncio
import contextlib
import socket
import struct
from collections.abc import AsyncIterator, Awaitable, Callable

import pytest

from pymotoros.client.connection import FrameConnection, reply_matches
from pymotoros.client.errors import ConnectionLostError, RequestTimeoutError
from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port
from pymotoros.protocol.framing import FrameDecoder, decode_request, encode
from pymotoros.protocol.messages import (
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
    Ping,
    PingReply,
)

LE = ByteOrder.LITTLE
Behaviour = Callable[[bytes, asyncio.StreamWriter], Awaitable[None]]


@contextlib.asynccontextmanager
async def raw_server(behaviour: Behaviour) -> AsyncIterator[int]:
    """A server that decodes each request and lets ``behaviour`` write whatever it likes."""
    tasks: set[asyncio.Task[None]] = set()

    async def handle(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        decoder = FrameDecoder(LE)
        try:
            while data := await reader.read(4096):
                decoder.feed(data)
                for frame in decoder.frames():
                    await behaviour(
                        encode(_reply(decode_request(frame, LE, Port.MOTION)), LE), writer
                    )
        finally:
            writer.close()

    def accept(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.get_running_loop().create_task(handle(reader, writer))
        tasks.add(task)
        task.add_done_callback(tasks.discard)

    server = await asyncio.start_server(accept, "127.0.0.1", 0)
    try:
        yield server.sockets[0].getsockname()[1]
    finally:
        server.close()
        for t in list(tasks):
            t.cancel()
            with contextlib.suppress(asyncio.CancelledError, ConnectionError):
                await t
        await server.wait_closed()


def _reply(msg: object) -> MotoMotionReply | PingReply:
    if isinstance(msg, MotoMotionCtrl):
        return MotoMotionReply(msg.group_no, msg.sequence, msg.command, 0, 7)
    return PingReply()


async def _open(port: int) -> FrameConnection:
    return await FrameConnection.open("127.0.0.1", port, Port.MOTION, LE, timeout_s=2.0)


@pytest.mark.parametrize("chunk", [1, 3, 7, 1024])
async def test_replies_in_pieces_are_reassembled(chunk: int) -> None:
    async def dribble(data: bytes, writer: asyncio.StreamWriter) -> None:
        for i in range(0, len(data), chunk):
            writer.write(data[i : i + chunk])
            await writer.drain()
            await asyncio.sleep(0)

    async with raw_server(dribble) as port:
        conn = await _open(port)
        try:
            for seq in range(3):
                request = MotoMotionCtrl(0, seq, int(MotionCommand.CHECK_QUEUE_CNT))
                reply = await conn.request(request, MotoMotionReply, timeout_s=2.0)
                assert isinstance(reply, MotoMotionReply)
                assert (reply.sequence, reply.subcode) == (seq, 7)
        finally:
            await conn.close()


async def test_stale_reply_before_the_right_one_is_skipped() -> None:
    async def stale_first(data: bytes, writer: asyncio.StreamWriter) -> None:
        writer.write(encode(MotoMotionReply(0, 999, 200102, 0, 1), LE) + data)  # one segment
        await writer.drain()

    async with raw_server(stale_first) as port:
        conn = await _open(port)
        try:
            reply = await conn.request(
                MotoMotionCtrl(0, 5, int(MotionCommand.CHECK_QUEUE_CNT)),
                MotoMotionReply,
                timeout_s=2.0,
            )
            assert isinstance(reply, MotoMotionReply)
            assert reply.sequence == 5
        finally:
            await conn.close()


async def test_silence_is_a_timeout_and_a_close_fails_waiters() -> None:
    async def silent(data: bytes, writer: asyncio.StreamWriter) -> None:
        return None

    async with raw_server(silent) as port:
        conn = await _open(port)
        try:
            with pytest.raises(RequestTimeoutError):
                await conn.request(Ping(), PingReply, timeout_s=0.1)
            waiting = asyncio.create_task(conn.request(Ping(), PingReply, timeout_s=5.0))
            await asyncio.sleep(0)
            await conn.close()
            async with asyncio.timeout(1):
                with pytest.raises(ConnectionLostError, match="closed by the client"):
                    await waiting
            with pytest.raises(ConnectionLostError):
                await conn.request(Ping(), PingReply, timeout_s=1.0)
        finally:
            await conn.close()


async def test_peer_closing_fails_the_request_at_once() -> None:
    async def hang_up(data: bytes, writer: asyncio.StreamWriter) -> None:
        writer.close()

    async with raw_server(hang_up) as port:
        conn = await _open(port)
        try:
            async with asyncio.timeout(2):
                with pytest.raises(ConnectionLostError, match="closed by the controller"):
                    await conn.request(Ping(), PingReply, timeout_s=5.0)
            assert conn.closed.is_set()
        finally:
            await conn.close()


def test_reply_matching_rules() -> None:
    ctrl = MotoMotionCtrl(0, 4, int(MotionCommand.STOP_MOTION))
    assert reply_matches(ctrl, MotoMotionReply(0, 4, 200111, 0, 0), MotoMotionReply)
    assert not reply_matches(ctrl, MotoMotionReply(0, 5, 200111, 0, 0), MotoMotionReply)
    assert not reply_matches(ctrl, MotoMotionReply(0, 4, 200102, 0, 0), MotoMotionReply)
    io = MotoReadIoBit(10010)
    assert reply_matches(io, MotoReadIoBitReply(1, 0), MotoReadIoBitReply)
    # An unknown request is answered with its own type echoed and sequence -1 (3003).
    assert reply_matches(io, MotoMotionReply(-1, -1, 2003, 3, 3003), MotoReadIoBitReply)
    assert not reply_matches(io, PingReply(), MotoReadIoBitReply)


async def test_a_reset_before_any_answer_on_the_motion_port_names_the_one_client_rule() -> None:
    """A controller that closes a second motion client with its request unread resets the
    socket (RST, not FIN): the client must say why (MotoROS's one motion connection), not
    only "Connection reset by peer" (seen once in four runs of a second `pymotoros move`)."""
    async def reset_after_the_first_request(
        reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        await reader.read(1)  # the request is there, most of it unread
        sock = writer.get_extra_info("socket")
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        writer.transport.abort()

    server = await asyncio.start_server(reset_after_the_first_request, "127.0.0.1", 0)
    async with server:
        conn = await _open(server.sockets[0].getsockname()[1])
        with pytest.raises(ConnectionLostError) as info:
            await conn.request(
                MotoMotionCtrl(0, 0, MotionCommand.CHECK_MOTION_READY),
                MotoMotionReply,
                timeout_s=2.0,
            )
        await conn.close()
    text = str(info.value)
    assert "MotoROS takes one motion connection" in text, text
    assert "the socket was reset" in text, text
