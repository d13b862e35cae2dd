"""docs/fidelity.md §1, row by row, in both settings: exact behaves as MotoROS 1.9.12,
safe as the twin's kinder version.

Each test talks raw bytes to the in-memory twin (``pymotoros.testing.Twin``, virtual
time): a client write lands in the server's stream at once and one read of the server
returns what has landed, up to what it asks for (552 bytes in exact, as ``recv`` on the
robot). Waiting for a reply before writing again therefore puts the next bytes in a read
of their own, deterministically.
"""

from __future__ import annotations

import asyncio
import contextlib
import struct
from collections.abc import AsyncIterator

import pytest

from pymotoros.models.fidelity import Fidelity
from pymotoros.protocol.constants import (
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    ByteOrder,
    InvalidSubcode,
    MotionCommand,
    MsgType,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import (
    IoErrorReply,
    JointTrajPtExData,
    JointTrajPtFull,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
    Ping,
    PingReply,
    WireMessage,
)
from pymotoros.runtime.motion_server import ZERO_REPLY_BUFFER
from pymotoros.testing import Twin

from .peer import Peer

LE = "<"
EXACT, SAFE = Fidelity.EXACT, Fidelity.SAFE
BOTH = pytest.mark.parametrize("fidelity", [EXACT, SAFE], ids=["exact", "safe"])
QUEUE_CNT = MotionCommand.CHECK_QUEUE_CNT
TIMEOUT_S = 5.0


class Raw(Peer):
    """A raw client of one twin port: bytes out, decoded replies in."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, port: Port):
        super().__init__(reader, writer, port, ByteOrder.LITTLE)

    async def write(self, data: bytes) -> None:
        await self.send_raw(data)

    async def reply(self) -> WireMessage:
        """The next reply (whole frames, cut by their prefix: what the twin sends is exact)."""
        return await self.message()

    async def request_ping(self) -> WireMessage:
        await self.write(encode(Ping(), LE))
        return await self.reply()

    async def raw(self, n: int) -> bytes:
        async with asyncio.timeout(TIMEOUT_S):
            return await self.reader.readexactly(n)

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(OSError):
            await self.writer.wait_closed()


@pytest.fixture
async def exact_twin() -> AsyncIterator[Twin]:
    async with Twin(fidelity=EXACT) as the_twin:
        yield the_twin


@contextlib.asynccontextmanager
async def connected(fidelity: Fidelity, port: int = TCP_PORT_MOTION) -> AsyncIterator[Raw]:
    """A twin in ``fidelity`` and a raw client of its ``port``, closed afterwards."""
    async with Twin(fidelity=fidelity) as twin:
        reader, writer = await twin.connect("test", port)
        peer = Raw(reader, writer, Port.MOTION if port == TCP_PORT_MOTION else Port.IO)
        try:
            yield peer
        finally:
            await peer.close()


def queue_cnt(sequence: int) -> bytes:
    return encode(MotoMotionCtrl(0, sequence, QUEUE_CNT), LE)


async def with_prefix(peer: Raw, message: bytes, prefix: int) -> WireMessage:
    """The reply to ``message`` sent with its length prefix replaced by ``prefix``."""
    data = bytearray(message)
    struct.pack_into("<i", data, 0, prefix)
    await peer.write(bytes(data))
    return await peer.reply()


def counted(sequence: int) -> MotoMotionReply:
    """CHECK_QUEUE_CNT's answer with an empty queue."""
    return MotoMotionReply(0, sequence, QUEUE_CNT, ResultCode.SUCCESS, 0)


# ------------------------------------------------------------------ framing (§1.5)


@BOTH
async def test_a_message_split_across_two_reads(fidelity: Fidelity) -> None:
    """exact: the first piece is answered INVALID/3001 (sequence and command echoed, group
    0) and the tail parsed as a new message: 3003; safe: reassembled, answered once."""
    async with connected(fidelity) as peer:
        data = queue_cnt(7)
        await peer.write(data[:30])
        if fidelity is EXACT:
            first = await peer.reply()
            assert first == MotoMotionReply(0, 7, QUEUE_CNT, ResultCode.INVALID, 3001)
            await peer.write(data[30:])
            # the tail's "type" is the bytes at its offset 4: a zero float of data[]
            assert await peer.reply() == MotoMotionReply(-1, -1, 0, ResultCode.INVALID, 3003)
        else:
            await asyncio.sleep(0)  # the server reads the first piece alone
            await peer.write(data[30:])
            assert await peer.reply() == counted(7)
        assert isinstance(await peer.request_ping(), PingReply)


@BOTH
async def test_fewer_than_16_bytes_in_a_read(fidelity: Fidelity) -> None:
    """exact: 3001 with group, sequence −1 and the command the type bytes give (here the
    type arrived: 2001 is a sequenced type, so group 0, sequence and command zero-filled);
    safe: waits for the rest."""
    async with connected(fidelity) as peer:
        data = queue_cnt(3)
        await peer.write(data[:10])
        if fidelity is EXACT:
            assert await peer.reply() == MotoMotionReply(0, 0, 0, ResultCode.INVALID, 3001)
            return
        await asyncio.sleep(0)
        await peer.write(data[10:])
        assert await peer.reply() == counted(3)


@BOTH
async def test_the_length_prefix_is_never_read(fidelity: Fidelity) -> None:
    """A CHECK_QUEUE_CNT whose prefix says 60 instead of 64: exact sizes it by its type and
    answers it; safe cuts the frame by the prefix and answers 3001."""
    async with connected(fidelity) as peer:
        reply = await with_prefix(peer, queue_cnt(4), 60)
        if fidelity is EXACT:
            assert reply == counted(4)
            assert isinstance(await peer.request_ping(), PingReply)
        else:
            assert reply == MotoMotionReply(0, 4, QUEUE_CNT, ResultCode.INVALID, 3001)


@BOTH
async def test_a_prefix_outside_12_to_548(fidelity: Fidelity) -> None:
    """exact: not looked at, the message is served; safe: INVALID/3001 and the buffered
    bytes dropped, the connection kept."""
    async with connected(fidelity) as peer:
        reply = await with_prefix(peer, queue_cnt(5), 100_000)
        if fidelity is EXACT:
            assert reply == counted(5)
        else:
            assert reply == MotoMotionReply(-1, -1, 0, ResultCode.INVALID, 3001)
        assert isinstance(await peer.request_ping(), PingReply)


@BOTH
async def test_pipelined_messages_whose_read_ends_mid_message(fidelity: Fidelity) -> None:
    """A PING and half a CHECK_QUEUE_CNT in one write, the rest in the next: MotoROS keeps
    the half and writes the next read out of bounds (undefined); exact joins the two, as
    the code means to, and so does safe: both are answered."""
    async with connected(fidelity) as peer:
        data = queue_cnt(6)
        await peer.write(encode(Ping(), LE) + data[:40])
        assert isinstance(await peer.reply(), PingReply)
        await peer.write(data[40:])
        assert await peer.reply() == counted(6)


@BOTH
async def test_more_than_552_bytes_in_one_write(fidelity: Fidelity) -> None:
    """Nine CHECK_QUEUE_CNT (612 bytes) in one write: exact reads 552 (eight and 8 bytes of
    the ninth), keeps the 8 and joins them with the next read; every request is answered,
    in order, in both settings."""
    async with connected(fidelity) as peer:
        await peer.write(b"".join(queue_cnt(s) for s in range(1, 10)))
        assert [await peer.reply() for _ in range(9)] == [counted(s) for s in range(1, 10)]


async def test_exact_reads_at_most_552_bytes(exact_twin: Twin) -> None:
    """The read size of exact is the robot's: a 4-group FULL_EX fits, nothing larger."""
    from pymotoros.protocol.receiver import RECV_SIZE, MotoRosReceiver

    assert RECV_SIZE == 552
    receiver = MotoRosReceiver(LE, Port.MOTION)
    assert receiver.read_size == 552
    receiver.feed(queue_cnt(1) + queue_cnt(2)[:20])
    assert receiver.turn().frame.msg_type == MsgType.MOTO_MOTION_CTRL
    assert receiver.wants_read
    assert receiver.read_size == 552 - 20  # the kept bytes count
    with pytest.raises(ValueError, match="at most 532"):
        receiver.feed(bytes(533))


@BOTH
async def test_io_port_split_message(fidelity: Fidelity) -> None:
    """The IO port reads the same way: exact answers the first piece with the IO error
    reply 3001; safe reassembles."""
    async with connected(fidelity, TCP_PORT_IO) as peer:
        data = encode(MotoReadIoBit(10010), LE)
        await peer.write(data[:12])
        if fidelity is EXACT:
            assert await peer.reply() == IoErrorReply(ResultCode.INVALID, 3001)
            await peer.write(data[12:])  # 8 bytes: fewer than a header again
            assert await peer.reply() == IoErrorReply(ResultCode.INVALID, 3001)
        else:
            await asyncio.sleep(0)
            await peer.write(data[12:])
            assert isinstance(await peer.reply(), MotoReadIoBitReply)


# ------------------------------------------------------------------ stale replies (§3.1, §3.5)


@BOTH
async def test_unknown_motion_ctrl_command(fidelity: Fidelity) -> None:
    """exact: no reply is built, MotoROS's reply buffer is sent again: four zero bytes on a
    fresh connection (a zero buffer, whose prefix says 0), else the previous reply, which
    can read as a success. safe: INVALID/3006."""
    async with connected(fidelity) as peer:
        unknown = encode(MotoMotionCtrl(0, 9, 200199), LE)
        await peer.write(unknown)
        if fidelity is SAFE:
            reply = await peer.reply()
            assert reply == MotoMotionReply(0, 9, 200199, ResultCode.INVALID, 3006)
            return
        assert await peer.raw(4) == ZERO_REPLY_BUFFER
        await peer.write(queue_cnt(8))
        assert await peer.reply() == counted(8)
        await peer.write(unknown)
        assert await peer.reply() == counted(8)  # stale: the previous reply, a "success"
        assert isinstance(await peer.request_ping(), PingReply)
        await peer.write(unknown)
        assert isinstance(await peer.reply(), PingReply)  # stale again: the PING's reply


@BOTH
async def test_full_ex_with_no_valid_groups(fidelity: Fidelity) -> None:
    """JOINT_TRAJ_PT_FULL_EX with numberOfValidGroups 0 or −1: exact sends the previous
    reply again (the reply buffer is left unset, §3.5); safe answers INVALID/3010 with
    group −1."""
    async with connected(fidelity) as peer:
        await peer.write(queue_cnt(2))
        assert await peer.reply() == counted(2)
        for n in (0, -1):
            full_ex = struct.pack("<iiiiii", 20, MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX, 2, 0, n, 11)
            await peer.write(full_ex)
            reply = await peer.reply()
            if fidelity is EXACT:
                assert reply == counted(2)
            else:
                assert reply == MotoMotionReply(-1, 11, 2016, ResultCode.INVALID, 3010)


@BOTH
async def test_a_nan_velocity_is_refused_in_both(fidelity: Fidelity) -> None:
    """Undefined behaviour of the C code (abs((int)NaN)) stays safe in both: 3013."""
    async with connected(fidelity) as peer:
        await peer.write(encode(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE), LE))
        assert (await peer.reply()).result == ResultCode.SUCCESS  # type: ignore[union-attr]
        start = JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6)
        await peer.write(encode(start, LE))
        assert (await peer.reply()).result == ResultCode.SUCCESS  # type: ignore[union-attr]
        bad = JointTrajPtFull.for_joints(0, 1, 1.0, [0.1] + [0.0] * 5, [float("nan")] + [0.0] * 5)
        await peer.write(encode(bad, LE))
        reply = await peer.reply()
        assert isinstance(reply, MotoMotionReply)
        assert (reply.result, reply.subcode) == (ResultCode.INVALID, InvalidSubcode.DATA_SPEED)


@BOTH
async def test_stale_reply_is_the_last_reply_built_even_unsent(fidelity: Fidelity) -> None:
    """A request sent as SERVICE_REPLY is processed and its reply built but not sent
    (§1.1); in exact that built reply is what an unknown command then gets."""
    async with connected(fidelity) as peer:
        as_reply = bytearray(queue_cnt(12))
        struct.pack_into("<i", as_reply, 8, 3)  # comm_type SERVICE_REPLY
        await peer.write(bytes(as_reply))
        await peer.write(encode(MotoMotionCtrl(0, 13, 200199), LE))
        reply = await peer.reply()
        if fidelity is EXACT:
            assert reply == counted(12)  # never sent before: built for the first request
        else:
            assert reply == MotoMotionReply(0, 13, 200199, ResultCode.INVALID, 3006)


@BOTH
async def test_a_full_ex_padded_to_552_bytes(fidelity: Fidelity) -> None:
    """A FULL_EX with one group padded to the full 552 bytes (prefix 548): the padding is
    ignored in both settings (§1.5), and the next request is served normally."""
    async with connected(fidelity) as peer:
        record = JointTrajPtExData.for_joints(0, 0.0, [0.0] * 6, [0.0] * 6).pack(LE)
        body = (struct.pack("<ii", 1, 0) + record).ljust(536, b"\0")
        await peer.write(struct.pack("<iiii", 548, MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX, 2, 0) + body)
        reply = await peer.reply()
        assert isinstance(reply, MotoMotionReply)
        assert (reply.command, reply.sequence) == (2016, 0)
        assert reply.result == ResultCode.NOT_READY  # trajectory mode is not on: processed
        assert isinstance(await peer.request_ping(), PingReply)


# ------------------------------------------------------------ connections (§2.2)


@BOTH
async def test_a_closed_connections_late_close_leaves_the_next_one_running(
    fidelity: Fidelity,
) -> None:
    """Client A closes and B connects before A's close has finished: B keeps its motion
    tasks and OT#893 (the robot ends them only when no motion connection is left)."""
    async with Twin(fidelity=fidelity) as twin:
        first = Raw(*await twin.connect("a", TCP_PORT_MOTION), Port.MOTION)
        assert isinstance(await first.request_ping(), PingReply)
        first.writer.close()
        for _ in range(100):  # bounded: a few loop turns
            if twin.motion.clients == 0:
                break  # A's slot is free; its close is still under way
            await asyncio.sleep(0)
        second = Raw(*await twin.connect("b", TCP_PORT_MOTION), Port.MOTION)
        io = Raw(*await twin.connect("io", TCP_PORT_IO), Port.IO)
        await twin.sleep(0.1)  # A's close completes
        assert isinstance(await second.request_ping(), PingReply)
        await io.write(encode(MotoReadIoBit(11124), LE))  # OT#893: motion server connected
        read = await io.reply()
        assert isinstance(read, MotoReadIoBitReply)
        assert read.value == 1, "a closed connection's late close ended the new one's tasks"
        for peer in (second, io):
            await peer.close()
