"""Reading recordings back (:func:`pymotoros.client.recording.read_recording`)."""

from __future__ import annotations

import itertools
from pathlib import Path

import dpkt
import pytest

from pymotoros.client.recorder import SessionRecorder, record_session
from pymotoros.client.recording import Direction, RecordingError, read_recording
from pymotoros.protocol.constants import ByteOrder, Port
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import (
    IoErrorReply,
    JointFeedback,
    MotoMotionReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
)
from pymotoros.testing import twin

IO_READS = 3


async def test_a_twin_session_reads_back_message_by_message(tmp_path: Path) -> None:
    pcap = tmp_path / "twin.pcapng"
    with record_session(pcap):
        async with twin(robot="hc10") as (client, _):
            for _ in range(IO_READS):
                await client.read_io_bit(10010)
    rec = read_recording(pcap)
    assert rec.order is ByteOrder.LITTLE
    kinds = {c.kind for c in rec.connections}
    assert Port.IO in kinds
    assert Port.STATE in kinds
    (io,) = rec.on(Port.IO)
    assert io.server_port == 50242
    sent = io.sent()
    received = io.received()
    assert [type(m.message) for m in sent] == [MotoReadIoBit] * IO_READS
    assert [type(m.message) for m in received] == [MotoReadIoBitReply] * IO_READS
    # request, reply, request, reply …: the file order, not a re-sort
    assert [m.direction for m in io.messages] == [
        Direction.TO_SERVER,
        Direction.FROM_SERVER,
    ] * IO_READS
    assert all(m.problem is None for m in rec.messages)
    # times: absolute and relative to the first packet agree, and never go back
    assert rec.chunks[0].offset >= 0.0
    assert all(c.time - rec.start == pytest.approx(c.offset) for c in rec.chunks)
    offsets = [m.offset for m in rec.messages]
    assert offsets == sorted(offsets)
    assert rec.duration >= offsets[-1]
    # the client closed every connection, and the recording shows its FIN
    assert all(c.closed is not None for c in rec.connections)
    # the state port: topics from the controller only, feedback among them
    for conn in rec.on(Port.STATE):
        assert conn.sent() == ()
        assert all(m.is_topic for m in conn.received())
    feedback = [m for m in rec.messages if isinstance(m.message, JointFeedback)]
    assert feedback
    # the payload bytes are those of the chunks, whole
    assert sum(len(c.payload) for c in io.chunks) == sum(m.frame.size for m in io.messages)


async def test_fs100_recording_is_read_big_endian(tmp_path: Path) -> None:
    pcap = tmp_path / "fs100.pcapng"
    with record_session(pcap):
        async with twin(controller="fs100") as (client, _):
            await client.read_io_bit(10010)
            seen = client.state.positions()
    assert seen is not None
    rec = read_recording(pcap)
    assert rec.order is ByteOrder.BIG
    (io,) = rec.on(Port.IO)
    assert io.sent()[0].message == MotoReadIoBit(10010)
    feedback = [m.message for m in rec.messages if isinstance(m.message, JointFeedback)]
    assert feedback
    # what the client saw is what the file holds, read in the FS100's byte order
    assert any(tuple(f.pos[: len(seen)]) == seen for f in feedback)


def _frame_split_recording(path: Path, times: list[float]) -> None:
    """One IO request written in two chunks, its reply in one, at the given clock times."""
    clock = iter(times)
    rec = SessionRecorder(path, clock=lambda: next(clock))
    flow = rec.flow(40000)  # a non-standard server port: the traffic says it is IO
    data = encode(MotoReadIoBit(10010), ByteOrder.LITTLE)
    flow.sent(data[:7])
    flow.sent(data[7:])
    flow.received(encode(MotoReadIoBitReply(1, 0), ByteOrder.LITTLE))
    flow.closed()
    rec.close()


def test_a_frame_split_over_chunks_takes_the_time_of_the_last(tmp_path: Path) -> None:
    pcap = tmp_path / "split.pcapng"
    # SYN, SYN+ACK, ACK, chunk 1, chunk 2, reply, FIN
    _frame_split_recording(pcap, [100.0, 100.0, 100.0, 100.5, 101.25, 102.0, 103.0])
    rec = read_recording(pcap)
    (conn,) = rec.connections
    assert conn.kind is Port.IO
    assert (conn.server_port, conn.client_port) == (40000, 49152)
    assert len(conn.chunks) == 3
    request, reply = conn.messages
    assert request.message == MotoReadIoBit(10010)
    assert request.time == 101.25
    assert request.offset == pytest.approx(1.25)
    assert reply.message == MotoReadIoBitReply(1, 0)
    assert reply.offset == pytest.approx(2.0)
    assert conn.closed == pytest.approx(3.0)


def test_the_port_can_be_named_when_the_traffic_does_not_say(tmp_path: Path) -> None:
    """2002 from the server is an IO error reply on the IO port, a MOTION_REPLY on motion."""
    pcap = tmp_path / "named.pcapng"
    rec = SessionRecorder(pcap)
    flow = rec.flow(40001)
    flow.received(encode(IoErrorReply(3, 0), ByteOrder.LITTLE))
    rec.close()
    (conn,) = read_recording(pcap).connections
    assert conn.kind is None
    assert conn.messages[0].message is None
    assert "port" in (conn.messages[0].problem or "")
    (conn,) = read_recording(pcap, ports={40001: Port.IO}).connections
    assert conn.messages[0].message == IoErrorReply(3, 0)
    assert not isinstance(conn.messages[0].message, MotoMotionReply)


def test_a_text_file_is_refused_clearly(tmp_path: Path) -> None:
    path = tmp_path / "notes.pcapng"
    path.write_text("not a capture\n")
    with pytest.raises(RecordingError, match="not a pcapng file"):
        read_recording(path)
    with pytest.raises(RecordingError, match="cannot open"):
        read_recording(tmp_path / "missing.pcapng")


def test_a_capture_of_other_traffic_is_refused_clearly(tmp_path: Path) -> None:
    path = tmp_path / "http.pcapng"
    rec = SessionRecorder(path)
    rec.flow(80).sent(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
    rec.close()
    with pytest.raises(RecordingError, match="Simple Message length prefix"):
        read_recording(path)

    empty = tmp_path / "empty.pcapng"
    SessionRecorder(empty).close()
    with pytest.raises(RecordingError, match="no TCP"):
        read_recording(empty)


def test_a_capture_with_lost_bytes_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "gap.pcapng"
    rec = SessionRecorder(path)
    flow = rec.flow(50242)
    data = encode(MotoReadIoBit(10010), ByteOrder.LITTLE)
    flow.sent(data)
    # a segment 10 bytes beyond where the stream is: bytes in between were lost
    seq = itertools.count(1001 + len(data) + 10)
    rec.write(flow.client, flow.server, next(seq), 1001, dpkt.tcp.TH_ACK, data)
    rec.close()
    with pytest.raises(RecordingError, match="not whole"):
        read_recording(path)
