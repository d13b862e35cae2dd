"""``lint_recording`` on recordings built message by message: the estimates a recording
allows (a reconnect over queued increments, a starved queue) and the sequence checks
across connections."""

from __future__ import annotations

import struct
from pathlib import Path

from pymotoros.cli.lint import lint_recording
from pymotoros.client.recording import (
    Direction,
    RecordedChunk,
    RecordedConnection,
    RecordedMessage,
    Recording,
)
from pymotoros.protocol.constants import ByteOrder, MotionCommand, MsgType, Port, ResultCode
from pymotoros.protocol.framing import FrameDecoder, encode
from pymotoros.protocol.messages import (
    JointTrajPtExData,
    JointTrajPtFull,
    Message,
    MotoMotionCtrl,
    MotoMotionReply,
)

ORDER = ByteOrder.LITTLE
MOTION, STATE = 50240, 50241


def _wire(msg: Message | bytes) -> bytes:
    """A message's bytes; raw bytes as they are (a frame no encoder writes)."""
    return msg if isinstance(msg, bytes) else encode(msg, ORDER)


def _message(
    conn: int, port: int, t: float, direction: Direction, msg: Message | bytes
) -> RecordedMessage:
    decoder = FrameDecoder(ORDER)
    decoder.feed(_wire(msg))
    frame = decoder.next_frame()
    assert frame is not None
    kind = Port.MOTION if port == MOTION else Port.STATE
    decoded = None if isinstance(msg, bytes) else msg  # raw: no decoder reads it
    return RecordedMessage(t, t, conn, port, 40000 + conn, kind, direction, frame, decoded)


def _connection(
    index: int,
    port: int,
    opened: float,
    closed: float | None,
    exchanges: list[tuple[float, Message | bytes, Message]],
) -> RecordedConnection:
    messages: list[RecordedMessage] = []
    chunks: list[RecordedChunk] = []
    for t, request, reply in exchanges:
        for when, direction, msg in (
            (t, Direction.TO_SERVER, request),
            (t, Direction.FROM_SERVER, reply),
        ):
            recorded = _message(index, port, when, direction, msg)
            messages.append(recorded)
            chunks.append(
                RecordedChunk(when, when, index, port, 40000 + index, direction, _wire(msg))
            )
    kind = Port.MOTION if port == MOTION else Port.STATE
    return RecordedConnection(
        index,
        port,
        40000 + index,
        kind,
        ORDER,
        opened,
        closed,
        tuple(chunks),
        tuple(messages),
        client=f"127.0.0.1:{40000 + index}",
    )


def _point(seq: int, time: float, pos: float, vel: float) -> tuple[Message, Message]:
    request = JointTrajPtFull.for_joints(0, seq, time, [pos] + [0.0] * 5, [vel] + [0.0] * 5)
    reply = MotoMotionReply(0, seq, 14, ResultCode.SUCCESS, 0, (0.0,) * 10)
    return request, reply


def _recording(*connections: RecordedConnection, end: float = 10.0) -> Recording:
    messages = tuple(m for c in connections for m in c.messages)
    chunks = tuple(ch for c in connections for ch in c.chunks)
    return Recording(Path("synthetic.pcapng"), 0.0, end, connections, chunks, messages)


def _codes(recording: Recording) -> list[str]:
    return sorted(str(f.code) for f in lint_recording(recording).findings())


def _state() -> RecordedConnection:
    return _connection(0, STATE, 0.0, None, [])


def _stream(
    index: int,
    opened: float,
    closed: float | None,
    points: list[tuple[float, int, float, float, float]],
) -> RecordedConnection:
    return _connection(
        index, MOTION, opened, closed, [(t, *_point(s, tt, p, v)) for t, s, tt, p, v in points]
    )


def test_a_reconnect_before_the_queue_ran_out_would_resume_it() -> None:
    first = _stream(1, 0.5, 1.5, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 2.0, 0.4, 0.2)])
    second = _stream(2, 1.6, None, [(1.7, 2, 4.0, 0.8, 0.0)])  # carries on: 2 after 1
    assert _codes(_recording(_state(), first, second)) == ["reconnect-resumed-motion"]


def test_a_reconnect_that_stops_first_is_no_finding() -> None:
    """STOP_MOTION as the first request of the new connection (what our client sends):
    the resumed increments are stopped at once, as on the twin."""
    first = _stream(1, 0.5, 1.5, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 2.0, 0.4, 0.0)])
    stop = MotoMotionCtrl(0, 0, MotionCommand.STOP_MOTION, (0.0,) * 10)
    stopped = MotoMotionReply(0, 0, MotionCommand.STOP_MOTION, ResultCode.SUCCESS, 0, (0.0,) * 10)
    second = _connection(2, MOTION, 1.6, None, [(1.61, stop, stopped)])
    assert _codes(_recording(_state(), first, second)) == []


def test_a_silent_reconnect_is_found_when_it_closes() -> None:
    """Decided at the first request or at a close without one, as on the twin: not
    when the queue would have run out (a connection that stays open is undecided)."""
    first = _stream(1, 0.5, 1.5, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 2.0, 0.4, 0.0)])
    closes = _connection(2, MOTION, 1.6, 1.8, [])
    assert _codes(_recording(_state(), first, closes)) == ["reconnect-resumed-motion"]
    closes_late = _connection(2, MOTION, 1.6, 4.0, [])  # after the queue would have run out
    assert _codes(_recording(_state(), first, closes_late)) == ["reconnect-resumed-motion"]
    stays = _connection(2, MOTION, 1.6, None, [])
    assert _codes(_recording(_state(), first, stays)) == []


def test_a_reconnect_that_stops_after_the_queue_ran_out_is_no_finding() -> None:
    first = _stream(1, 0.5, 1.5, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 2.0, 0.4, 0.0)])
    stop = MotoMotionCtrl(0, 0, MotionCommand.STOP_MOTION, (0.0,) * 10)
    stopped = MotoMotionReply(0, 0, MotionCommand.STOP_MOTION, ResultCode.SUCCESS, 0, (0.0,) * 10)
    late = _connection(2, MOTION, 1.6, None, [(4.0, stop, stopped)])  # the queue ended ~3 s
    assert _codes(_recording(_state(), first, late)) == []


def test_a_reconnect_after_the_queue_ran_out_resumes_nothing() -> None:
    first = _stream(1, 0.5, 1.5, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 2.0, 0.4, 0.0)])
    second = _stream(2, 3.5, None, [(3.6, 0, 0.0, 0.4, 0.0), (3.61, 1, 1.0, 0.0, 0.0)])
    assert _codes(_recording(_state(), first, second)) == []


def test_a_stream_that_stops_moving_starves() -> None:
    moving_end = _stream(1, 0.5, None, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 0.5, 0.05, 0.2)])
    assert _codes(_recording(_state(), moving_end)) == ["queue-starved"]
    at_rest = _stream(1, 0.5, None, [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 0.5, 0.05, 0.0)])
    assert _codes(_recording(_state(), at_rest)) == []


def test_a_late_point_after_a_moving_one_starved_the_queue() -> None:
    late = _stream(
        1,
        0.5,
        None,
        [(1.0, 0, 0.0, 0.0, 0.0), (1.01, 1, 0.5, 0.05, 0.2), (2.0, 2, 1.0, 0.1, 0.0)],
    )
    assert _codes(_recording(_state(), late)) == ["queue-starved"]


def test_the_motion_starts_with_the_first_point_after_sequence_0() -> None:
    """Seconds between point 0 and point 1 do not eat into the queue: the robot starts
    moving when point 1 is accepted."""
    slow_start = _stream(
        1,
        0.5,
        None,
        [(1.0, 0, 0.0, 0.0, 0.0), (6.0, 1, 0.5, 0.05, 0.2), (6.3, 2, 1.0, 0.1, 0.0)],
    )
    assert _codes(_recording(_state(), slow_start)) == []


def test_a_full_ex_padded_to_552_bytes_is_no_length_mismatch() -> None:
    """MotoROS takes a 552-byte FULL_EX whole (its message struct, §1.5), as the twin
    does: spare bytes elsewhere are a length mismatch."""
    record = JointTrajPtExData.for_joints(0, 0.0, [0.0] * 6, [0.0] * 6).pack("<")
    body = struct.pack("<ii", 1, 0) + record
    ex = MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    reply = MotoMotionReply(0, 0, 2016, ResultCode.SUCCESS, 0, (0.0,) * 10)

    def full_ex(size: int) -> bytes:
        return struct.pack("<iiii", size - 4, ex, 2, 0) + body.ljust(size - 16, b"\0")

    padded = _connection(1, MOTION, 0.5, None, [(1.0, full_ex(552), reply)])
    assert "length-mismatch" not in _codes(_recording(_state(), padded))
    spare = _connection(1, MOTION, 0.5, None, [(1.0, full_ex(548), reply)])
    assert "length-mismatch" in _codes(_recording(_state(), spare))
