"""The motion server's fast reply path (issue 13) sends exactly the bytes of the plain one.

``MotionServer._reply`` builds MOTO_MOTION_REPLY without the constructor's field checks,
and ``MotionServer.send`` encodes each distinct reply once; both must be invisible on
the wire, and the cache of encoded replies must stay bounded whatever a client sends.
"""

from __future__ import annotations

import asyncio

import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.api import Outcome
from pymotoros.protocol.constants import ByteOrder, MotionCommand, ResultCode
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import MotoMotionReply
from pymotoros.runtime import motion_server
from pymotoros.runtime.motion_server import ENCODED_REPLIES, MotionServer


class _Writer:
    """Records what the server writes (the part of StreamWriter that send() uses)."""

    def __init__(self) -> None:
        self.chunks: list[bytes] = []

    def write(self, data: bytes) -> None:
        self.chunks.append(bytes(data))

    async def drain(self) -> None:
        return None


class _Conn:
    peer = "test"

    def __init__(self) -> None:
        self.writer = _Writer()

    def write(self, data: bytes) -> None:  # as runtime.tcp.Connection, unrecorded
        self.writer.write(data)


@pytest.mark.parametrize("order", [ByteOrder.LITTLE, ByteOrder.BIG])
def test_replies_are_the_checked_messages_and_their_bytes(order: ByteOrder) -> None:
    server = MotionServer(VirtualController(), order)
    conn = _Conn()
    sent: list[bytes] = []
    cases = [
        (Outcome(ResultCode.SUCCESS, 0), 0, 5, int(MotionCommand.CHECK_QUEUE_CNT)),
        (Outcome(ResultCode.SUCCESS, 17), 1, -3, int(MotionCommand.CHECK_QUEUE_CNT)),
        (Outcome(ResultCode.NOT_READY, 5001, group_no=2), 0, 2**31 - 1, 200101),
    ]
    for outcome, group, sequence, command in cases * 2:  # the second round: cached
        reply = MotionServer._reply(outcome, group, sequence, command)
        checked = MotoMotionReply(
            group if outcome.group_no is None else outcome.group_no,
            sequence,
            command,
            int(outcome.result),
            outcome.subcode,
        )
        assert reply == checked
        assert repr(reply) == repr(checked)
        asyncio.run(server.send(conn, reply))  # type: ignore[arg-type]
        sent.append(encode(checked, order))
    assert conn.writer.chunks == sent


def test_the_cache_of_encoded_replies_is_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(motion_server, "ENCODED_REPLIES", 8)
    server = MotionServer(VirtualController(), ByteOrder.LITTLE)
    conn = _Conn()

    async def many() -> None:
        for sequence in range(100):  # a client counting its sequence numbers up
            reply = MotionServer._reply(Outcome(ResultCode.SUCCESS, 0), 0, sequence, 1)
            await server.send(conn, reply)  # type: ignore[arg-type]
            assert len(server._encoded) <= 8

    asyncio.run(many())
    expected = [
        encode(MotoMotionReply(0, sequence, 1, 0, 0), ByteOrder.LITTLE) for sequence in range(100)
    ]
    assert conn.writer.chunks == expected
    assert ENCODED_REPLIES >= 8


def test_a_reply_not_built_by_the_server_is_encoded_as_it_is() -> None:
    """-0.0 equals 0.0, so such a reply must not share a cache entry with _reply's."""
    server = MotionServer(VirtualController(), ByteOrder.LITTLE)
    conn = _Conn()
    plain = MotionServer._reply(Outcome(ResultCode.SUCCESS, 0), 0, 0, 1)
    negative = MotoMotionReply(0, 0, 1, 0, 0, (-0.0,) * 10)
    assert plain == negative

    async def both() -> None:
        await server.send(conn, plain)  # type: ignore[arg-type]
        await server.send(conn, negative)  # type: ignore[arg-type]

    asyncio.run(both())
    assert conn.writer.chunks == [
        encode(plain, ByteOrder.LITTLE),
        encode(negative, ByteOrder.LITTLE),
    ]
    assert conn.writer.chunks[0] != conn.writer.chunks[1]
