"""Client lint on the wire: for each code, a client that triggers it and a well-behaved
one that does not, against the real MotoROS server handlers in the in-memory twin.

The clients here are raw (bytes and messages written by hand), so that each one does
exactly the one thing under test.
"""

from __future__ import annotations

import asyncio
import struct
from collections.abc import AsyncIterator

import pytest

from pymotoros.controller.lint import MAX_FINDINGS, OTHER_CONNECTIONS, Finding, LintCode
from pymotoros.protocol.constants import (
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    TCP_PORT_STATE,
    InvalidSubcode,
    MotionCommand,
    MsgType,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import FrameDecoder, decode_reply, encode
from pymotoros.protocol.messages import (
    JointTrajPtExData,
    JointTrajPtFull,
    Message,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadIoBit,
    Ping,
)
from pymotoros.testing import TWIN_HOST, Twin

ZEROS = (0.0,) * 10


class RawClient:
    """One raw connection to a twin's port: writes what it is told, reads one reply."""

    def __init__(self, cell: Twin, streams: tuple[asyncio.StreamReader, asyncio.StreamWriter]):
        self.cell = cell
        self.order = cell.cell.controller.byte_order
        self.reader, self.writer = streams
        self.decoder = FrameDecoder(self.order)

    def frame(self, message: Message) -> bytes:
        return encode(message, self.order)

    def write(self, data: bytes) -> None:
        self.writer.write(data)

    async def reply(self, port: Port = Port.MOTION) -> object:
        async with asyncio.timeout(10):
            while (frame := self.decoder.next_frame()) is None:
                data = await self.reader.read(4096)
                assert data, "the twin closed the connection"
                self.decoder.feed(data)
        return decode_reply(frame, self.order, port)

    async def request(self, message: Message) -> MotoMotionReply:
        self.write(self.frame(message))
        reply = await self.reply()
        assert isinstance(reply, MotoMotionReply), reply
        return reply

    async def ctrl(self, command: int) -> MotoMotionReply:
        return await self.request(MotoMotionCtrl(0, 0, command, ZEROS))

    async def point(
        self, sequence: int, time: float, pos: float, vel: float = 0.0
    ) -> MotoMotionReply:
        return await self.request(
            JointTrajPtFull.for_joints(0, sequence, time, [pos] + [0.0] * 5, [vel] + [0.0] * 5)
        )

    def close(self) -> None:
        self.writer.close()


_OPEN: list[asyncio.StreamWriter] = []
"""The writers a test opened (closed after it: an unclosed writer warns)."""


@pytest.fixture
async def cell() -> AsyncIterator[Twin]:
    async with Twin(robot="hc10") as the_twin:
        try:
            yield the_twin
        finally:
            while _OPEN:
                _OPEN.pop().close()


async def _connect(cell: Twin, port: int = TCP_PORT_MOTION) -> RawClient:
    streams = await cell.connect(TWIN_HOST, port)
    _OPEN.append(streams[1])
    return RawClient(cell, streams)


async def _enabled(cell: Twin, *, state: bool = True) -> RawClient:
    """A motion connection in trajectory mode (and an open state connection if ``state``)."""
    if state:
        await _connect(cell, TCP_PORT_STATE)
        await cell.sleep(0.1)
    motion = await _connect(cell)
    reply = await motion.ctrl(MotionCommand.START_TRAJ_MODE)
    assert reply.result == ResultCode.SUCCESS, reply
    return motion


def _codes(cell: Twin) -> list[str]:
    return sorted(str(f.code) for f in cell.controller.lint.findings())


def _finding(cell: Twin, code: LintCode) -> Finding:
    found = [f for f in cell.controller.lint.findings() if f.code is code]
    assert found, f"no {code} among {_codes(cell)}"
    return found[0]


# ----------------------------------------------------------------- framing


async def test_a_message_in_two_writes_is_fragmented(cell: Twin) -> None:
    client = await _connect(cell)
    data = client.frame(Ping())
    client.write(data[:10])
    await cell.sleep(0.01)  # the twin reads the first piece on its own
    client.write(data[10:])
    await client.reply()  # safe: the Ping reassembled; exact: the first piece's 3001
    await cell.sleep(0.01)
    finding = _finding(cell, LintCode.FRAGMENTED_MESSAGE)
    assert finding.connection.startswith("twin-client-")
    assert finding.reference == "§1.5"
    assert "one write" in finding.remedy


async def test_a_message_in_one_write_is_not_fragmented(cell: Twin) -> None:
    client = await _connect(cell)
    for _ in range(3):
        await client.request(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT, ZEROS))
    assert _codes(cell) == []


@pytest.mark.parametrize("extra", [4, -4])
async def test_a_prefix_that_disagrees_with_the_type_is_a_length_mismatch(
    cell: Twin, extra: int
) -> None:
    client = await _connect(cell)
    data = client.frame(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT, ZEROS))
    length = struct.unpack(client.order + "i", data[:4])[0] + extra
    body = data[4:] + b"\0" * extra if extra > 0 else data[4:extra]
    client.write(struct.pack(client.order + "i", length) + body)
    reply = await client.reply()
    assert isinstance(reply, MotoMotionReply)
    if extra < 0:  # short of its type: 3001, as MotoROS answers a cut message (§1.5)
        assert (reply.result, reply.subcode) == (ResultCode.INVALID, InvalidSubcode.MSGSIZE)
    await cell.sleep(0.01)
    assert _finding(cell, LintCode.LENGTH_MISMATCH).reference == "§1.1"
    assert "fragmented-message" not in _codes(cell)  # one whole write: not a fragment


@pytest.mark.parametrize("prefix", [100_000, 4])
async def test_a_prefix_outside_12_to_548_is_a_length_mismatch(either: Twin, prefix: int) -> None:
    """exact serves it (the prefix is never read), safe answers INVALID/3001 and drops
    the bytes: a finding in both settings."""
    cell = either
    client = await _connect(cell)
    data = client.frame(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT, ZEROS))
    client.write(struct.pack(client.order + "i", prefix) + data[4:])
    assert isinstance(await client.reply(), MotoMotionReply)
    await cell.sleep(0.01)
    assert "length-mismatch" in _codes(cell)


async def test_the_io_port_finds_length_mismatches_too(cell: Twin) -> None:
    client = await _connect(cell, TCP_PORT_IO)
    data = client.frame(MotoReadIoBit(10010))
    client.write(data)  # well-behaved first
    await client.reply(Port.IO)
    assert _codes(cell) == []
    length = struct.unpack(client.order + "i", data[:4])[0] + 4
    client.write(struct.pack(client.order + "i", length) + data[4:] + b"\0" * 4)
    await client.reply(Port.IO)
    await cell.sleep(0.01)
    assert "length-mismatch" in _codes(cell)


# ----------------------------------------------------------------- stale replies


async def test_an_unknown_command_is_found_and_gets_a_stale_reply_on_a_robot(cell: Twin) -> None:
    client = await _connect(cell)
    await client.ctrl(MotionCommand.CHECK_QUEUE_CNT)  # a reply a stale one can repeat
    await client.ctrl(200199)
    assert _codes(cell) == ["stale-reply", "unknown-command"]
    assert _finding(cell, LintCode.UNKNOWN_COMMAND).reference == "§3.1"


async def test_known_commands_are_not_unknown(cell: Twin) -> None:
    client = await _connect(cell)
    for command in (MotionCommand.CHECK_MOTION_READY, MotionCommand.CHECK_QUEUE_CNT):
        await client.ctrl(command)
    assert _codes(cell) == []


async def test_full_ex_without_groups_gets_a_stale_reply_on_a_robot(cell: Twin) -> None:
    client = await _connect(cell)
    await client.ctrl(MotionCommand.CHECK_QUEUE_CNT)  # a reply a stale one can repeat
    # MOTO_JOINT_TRAJ_PT_FULL_EX with numberOfValidGroups 0: prefix, header, n, sequence.
    o = client.order
    client.write(struct.pack(o + "6i", 20, MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX, 2, 0, 0, 1))
    await client.reply()
    assert _codes(cell) == ["stale-reply"]


# ----------------------------------------------------------------- streaming


async def test_a_trajectory_that_ends_moving_starves_the_queue(cell: Twin) -> None:
    client = await _enabled(cell)
    assert (await client.point(0, 0.0, 0.0)).result == ResultCode.SUCCESS
    assert (await client.point(1, 0.5, 0.05, vel=0.2)).result == ResultCode.SUCCESS
    await cell.sleep(1.0)  # no more points: the queue runs dry at 0.2 rad/s
    assert _codes(cell) == ["queue-starved"]
    assert cell.controller.lint.findings()[0].first_s > 0.4


async def test_a_trajectory_that_ends_at_rest_does_not_starve(cell: Twin) -> None:
    client = await _enabled(cell)
    await client.point(0, 0.0, 0.0)
    await client.point(1, 0.5, 0.05, vel=0.2)
    while (await client.point(2, 1.0, 0.1)).result == ResultCode.BUSY:
        await cell.sleep(0.005)
    await cell.sleep(1.5)
    assert _codes(cell) == []


async def _stream(client: RawClient, sequences: list[int], *, resend_busy: bool) -> None:
    for k, sequence in enumerate(sequences):
        while True:
            pos = 0.01 * k
            moving = 0 < k < len(sequences) - 1  # at rest at both ends
            reply = await client.point(sequence, 0.1 * k, pos, vel=0.1 if moving else 0.0)
            if reply.result != ResultCode.BUSY or not resend_busy:
                break
            await client.cell.sleep(0.004)
        if reply.result == ResultCode.BUSY:
            await client.cell.sleep(0.2)


async def test_advancing_after_busy_skips_the_busy_point(cell: Twin) -> None:
    client = await _enabled(cell)
    await _stream(client, [0, 1, 2, 3], resend_busy=False)
    assert "busy-point-skipped" in _codes(cell)


async def test_resending_the_busy_point_skips_nothing(cell: Twin) -> None:
    client = await _enabled(cell)
    await _stream(client, [0, 1, 2, 3, 4], resend_busy=True)
    await cell.sleep(0.5)
    assert _codes(cell) == []


async def test_a_gap_in_the_sequence_is_found(cell: Twin) -> None:
    client = await _enabled(cell)
    await _stream(client, [0, 1, 3], resend_busy=True)
    assert "sequence-not-consecutive" in _codes(cell)


async def test_points_without_a_state_connection_are_found(cell: Twin) -> None:
    client = await _enabled(cell, state=False)
    await client.point(0, 0.0, 0.0)
    assert _codes(cell) == ["motion-without-state"]


async def test_points_with_a_state_connection_are_watched(cell: Twin) -> None:
    client = await _enabled(cell, state=True)
    await client.point(0, 0.0, 0.0)
    assert _codes(cell) == []


async def test_a_moto_style_full_ex_stream_gives_nothing(cell: Twin) -> None:
    """As the ``moto`` library streams: START_TRAJ_MODE, then one FULL_EX per point with
    the group's record, sequence 0, 1, 2 …, the same point again after BUSY."""
    client = await _enabled(cell)
    for k in range(6):
        last = k == 5
        record = JointTrajPtExData.for_joints(
            0, 0.1 * k, [0.01 * k] + [0.0] * 5, [0.0 if last or not k else 0.1] + [0.0] * 5
        )
        while (
            await client.request(MotoJointTrajPtFullEx.for_groups(k, [record]))
        ).result == ResultCode.BUSY:
            await cell.sleep(0.004)
    await cell.sleep(0.8)
    assert _codes(cell) == []


# ----------------------------------------------------------------- reconnects


async def _reconnect_over_queued_motion(cell: Twin) -> RawClient:
    """A motion connection streams a slow point, closes with increments queued, and a
    new one opens: in exact the queues were kept and the new connection resumes them."""
    client = await _enabled(cell)
    await client.point(0, 0.0, 0.0)
    await client.point(1, 2.0, 0.4, vel=0.0)
    await cell.sleep(0.2)
    assert cell.controller.has_queued_motion()
    client.close()
    await cell.sleep(0.1)
    return await _connect(cell)


@pytest.mark.parametrize(
    ("fidelity", "first", "found"),
    [
        ("exact", MotionCommand.CHECK_QUEUE_CNT, True),
        ("exact", MotionCommand.STOP_MOTION, False),
        ("safe", MotionCommand.CHECK_QUEUE_CNT, True),
        ("safe", MotionCommand.STOP_MOTION, False),
    ],
)
async def test_a_reconnect_is_found_when_it_lets_the_kept_increments_run(
    fidelity: str, first: int, found: bool
) -> None:
    """exact keeps the queues as MotoROS does (§2.2), and the next connection resumes
    them: a finding unless its first request is STOP_MOTION (what our client sends,
    docs/client.md), which stops the robot. safe cleared them at the close, so nothing
    moves, but the lint applies the same rule to what a robot would have resumed."""
    async with Twin(robot="hc10", fidelity=fidelity) as cell:
        try:
            client = await _reconnect_over_queued_motion(cell)
            await cell.sleep(0.1)
            assert _codes(cell) == []  # nothing sent yet: not decided
            assert (await client.ctrl(first)).result == ResultCode.SUCCESS
            await cell.sleep(0.1)
            assert ("reconnect-resumed-motion" in _codes(cell)) is found
            if found:
                finding = _finding(cell, LintCode.RECONNECT_RESUMED_MOTION)
                assert "CHECK_QUEUE_CNT" in finding.text
                assert finding.connection.startswith("twin-client-")
                cleared = "safe cleared them, but a robot would have kept them and resumed"
                assert (cleared in finding.text) is (fidelity == "safe"), finding.text
            else:
                assert not cell.controller.has_queued_motion()
        finally:
            while _OPEN:
                _OPEN.pop().close()


@pytest.fixture(params=["exact", "safe"])
async def either(request: pytest.FixtureRequest) -> AsyncIterator[Twin]:
    """A twin in each fidelity setting: the lint's findings are the same in both."""
    async with Twin(robot="hc10", fidelity=request.param) as the_twin:
        try:
            yield the_twin
        finally:
            while _OPEN:
                _OPEN.pop().close()


async def test_a_reconnect_that_stops_after_the_old_motion_ran_out_is_no_finding(
    either: Twin,
) -> None:
    """The old motion running out before the first request decides nothing: over TCP
    a connection lost in a move's last ticks would give a client that sends STOP_MOTION
    first a finding. The first request decides (or a close without one)."""
    cell = either
    client = await _reconnect_over_queued_motion(cell)
    await cell.sleep(3.0)
    assert not cell.controller.has_queued_motion()
    assert (await client.ctrl(MotionCommand.STOP_MOTION)).result == ResultCode.SUCCESS
    await cell.sleep(0.1)
    assert _codes(cell) == []


async def test_a_reconnect_that_closes_silently_is_found(either: Twin) -> None:
    cell = either
    client = await _reconnect_over_queued_motion(cell)
    await cell.sleep(0.1)
    client.close()
    await cell.sleep(0.1)
    finding = _finding(cell, LintCode.RECONNECT_RESUMED_MOTION)
    assert "closed without sending STOP_MOTION" in finding.text
    assert finding.first_s < cell.controller.time_ms / 1000.0 - 0.1  # when it opened


async def test_a_replaced_connections_pending_point_is_dropped(cell: Twin) -> None:
    """A new motion client replaces the old one while nothing is queued: MotoROS closes
    the old connection and deletes its tasks, which drops the pending point (§2.2), so
    the arm does not move to it under the new connection."""
    client = await _enabled(cell)
    await client.point(0, 0.0, 0.0)
    assert (await client.point(1, 1.0, 0.2)).result == ResultCode.SUCCESS  # pending
    assert not cell.controller.has_queued_motion()  # no tick has run: a replace is allowed
    await _connect(cell)  # replaces it
    await cell.sleep(1.5)
    assert cell.motion.replaced == 1
    assert abs(cell.controller.snapshot().groups[0].command_rad[0]) < 1e-6


async def test_a_reconnect_after_a_close_at_rest_is_no_finding(either: Twin) -> None:
    """Nothing was queued when the connection closed: nothing to resume, whatever the
    next connection sends first."""
    cell = either
    client = await _enabled(cell)
    await client.point(0, 0.0, 0.0)
    await client.point(1, 0.2, 0.01)
    await cell.sleep(0.6)
    assert not cell.controller.has_queued_motion()
    client.close()
    await cell.sleep(0.1)
    again = await _connect(cell)
    assert (await again.ctrl(MotionCommand.CHECK_QUEUE_CNT)).result == ResultCode.SUCCESS
    await cell.sleep(1.0)
    assert _codes(cell) == []


async def test_a_flood_of_connections_cannot_grow_the_findings(cell: Twin) -> None:
    """More misbehaving connections than the lint keeps: later ones share one entry per
    code, every occurrence is still counted."""
    connections = MAX_FINDINGS + 44
    for _ in range(connections):
        client = await _connect(cell)
        await client.ctrl(MotionCommand.CHECK_QUEUE_CNT)  # a reply a stale one can repeat
        await client.ctrl(200199)
        client.close()
        _OPEN.remove(client.writer)
    findings = cell.controller.lint.findings()
    assert len(findings) <= MAX_FINDINGS + len(LintCode)
    assert sum(f.count for f in findings) == 2 * connections
    assert {f.connection for f in findings} >= {OTHER_CONNECTIONS}
