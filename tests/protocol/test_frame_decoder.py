"""FrameDecoder on hostile streams: any split, one byte at a time, garbage, bad prefixes."""

from __future__ import annotations

import contextlib
import itertools
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sm_wire import BE, LE, Body, frame

from pymotoros.errors import RemoteProtocolError
from pymotoros.protocol import (
    ByteOrder,
    Frame,
    FrameDecoder,
    JointFeedback,
    MotoJointFeedbackEx,
    MotoMotionReply,
    MotoSelectTool,
    Port,
    RobotStatus,
    UnknownMessage,
    decode_reply,
    decode_request,
    encode_frame,
)

ORDER_OF = {LE: ByteOrder.LITTLE, BE: ByteOrder.BIG}


def _stream(o: str) -> tuple[bytes, list[Frame]]:
    """One state cycle of a 2-group controller plus a ping reply, as hand-built bytes."""
    feedback0 = Body(o, 132).i(0, 0).i(4, 6).f(12, 1.5).bytes()
    feedback1 = Body(o, 132).i(0, 1).i(4, 6).f(52, -0.5).bytes()
    ex = Body(o, 532).i(0, 2).bytes()
    status = Body(o, 28).i(0, 1).i(20, 2).bytes()
    parts = [
        (15, 1, 0, feedback0),
        (15, 1, 0, feedback1),
        (2017, 1, 0, ex),
        (13, 1, 0, status),
        (1, 3, 1, b""),
    ]
    data = b"".join(frame(o, *part) for part in parts)
    return data, [Frame(*part) for part in parts]


def _drain(decoder: FrameDecoder) -> list[Frame]:
    return list(decoder.frames())


@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_split_at_every_position(o: str) -> None:
    data, expected = _stream(o)
    for cut in range(len(data) + 1):
        decoder = FrameDecoder(ORDER_OF[o])
        decoder.feed(data[:cut])
        got = _drain(decoder)
        decoder.feed(data[cut:])
        got += _drain(decoder)
        assert got == expected, f"split at {cut}"
        assert decoder.buffered == 0


@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_one_byte_at_a_time(o: str) -> None:
    data, expected = _stream(o)
    decoder = FrameDecoder(ORDER_OF[o])
    got: list[Frame] = []
    boundaries = set()
    end = 0
    for f in expected:
        end += 16 + len(f.body)
        boundaries.add(end)
    for index in range(len(data)):
        decoder.feed(data[index : index + 1])
        frames = _drain(decoder)
        # a frame appears exactly when its last byte arrives, never earlier
        assert len(frames) == (1 if index + 1 in boundaries else 0)
        got += frames
    assert got == expected


@pytest.mark.parametrize("chunk", [1, 3, 7, 1024])
@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_fixed_chunk_sizes(o: str, chunk: int) -> None:
    data, expected = _stream(o)
    decoder = FrameDecoder(ORDER_OF[o])
    got: list[Frame] = []
    for start in range(0, len(data), chunk):
        decoder.feed(data[start : start + chunk])
        got += _drain(decoder)
    assert got == expected


@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_triad_next_frame_stays_buffered(o: str) -> None:
    """Whole frame, then the following frame's bytes must stay in the buffer."""
    data, expected = _stream(o)
    first = 16 + len(expected[0].body)
    decoder = FrameDecoder(ORDER_OF[o])
    decoder.feed(data[: first + 10])
    assert decoder.next_frame() == expected[0]
    assert decoder.next_frame() is None
    assert decoder.buffered == 10


@given(data=st.binary(max_size=1200), cuts=st.lists(st.integers(0, 1200), max_size=6))
@settings(max_examples=300)
def test_arbitrary_bytes_only_raise_remote_protocol_error(data: bytes, cuts: list[int]) -> None:
    decoder = FrameDecoder(ByteOrder.LITTLE)
    points = sorted({0, len(data), *(c for c in cuts if c <= len(data))})
    try:
        for start, stop in itertools.pairwise(points):
            decoder.feed(data[start:stop])
            for f in decoder.frames():
                for port in Port:
                    _decode_quietly(f, port)
    except RemoteProtocolError:
        pass


def _decode_quietly(f: Frame, port: Port) -> None:
    for decode in (decode_request, decode_reply):
        with contextlib.suppress(RemoteProtocolError):
            decode(f, ByteOrder.LITTLE, port)


@given(
    msg_type=st.sampled_from(
        [
            *(1, 2, 13, 14, 15, 2001, 2002, 2003, 2004, 2005, 2006, 2007, 2008, 2009, 2010),
            *(2011, 2012, 2013, 2016, 2017, 2018, 2020, -1, 0, 7),
        ]
    ),
    body=st.binary(max_size=536),
)
@settings(max_examples=400)
def test_any_body_for_any_type_decodes_or_raises_remote_error(msg_type: int, body: bytes) -> None:
    f = Frame(msg_type, 2, 0, body)
    for port in Port:
        _decode_quietly(f, port)


@pytest.mark.parametrize("prefix", [-1, -(2**31), 0, 4, 11, 549, 552, 1024, 2**31 - 1])
@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_bad_prefix_is_a_typed_error_carrying_the_bytes(o: str, prefix: int) -> None:
    bad = struct.pack(o + "iiii", prefix, 14, 2, 0) + b"\x55" * 20
    decoder = FrameDecoder(ORDER_OF[o])
    decoder.feed(bad)
    with pytest.raises(RemoteProtocolError, match=str(prefix)) as info:
        decoder.next_frame()
    assert info.value.data == bad
    # it keeps refusing until the caller resynchronises
    with pytest.raises(RemoteProtocolError):
        decoder.next_frame()
    assert decoder.discard() == bad
    assert decoder.buffered == 0
    decoder.feed(frame(o, 1, 2, 0))
    assert decoder.next_frame() == Frame(1, 2, 0, b"")


def test_bad_prefix_detected_from_the_prefix_alone() -> None:
    """No need to wait for 548 bytes: four bytes of prefix suffice to refuse."""
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(struct.pack("<i", 10_000))
    with pytest.raises(RemoteProtocolError):
        decoder.next_frame()


def test_largest_legal_prefix_is_accepted() -> None:
    data = frame(LE, 2016, 2, 0, bytes(536))
    assert len(data) == 552
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(data)
    assert decoder.next_frame() == Frame(2016, 2, 0, bytes(536))


def test_truncated_frame_waits_and_stays_bounded() -> None:
    data = frame(LE, 2001, 2, 0, bytes(52))
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(data[:-1])
    assert decoder.next_frame() is None
    assert decoder.buffered == len(data) - 1
    decoder.feed(data[-1:])
    f = decoder.next_frame()
    assert f is not None
    assert f.size == 68


def test_feed_accepts_bytearray_and_memoryview() -> None:
    data = frame(LE, 1, 3, 1)
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(bytearray(data[:5]))
    decoder.feed(memoryview(data)[5:])
    assert decoder.next_frame() == Frame(1, 3, 1, b"")


def test_many_frames_in_one_chunk_compact_the_buffer() -> None:
    one = frame(LE, 13, 1, 0, bytes(28))
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(one * 3000 + one[:7])
    assert sum(1 for _ in decoder.frames()) == 3000
    assert decoder.buffered == 7


def test_wrong_body_size_for_known_type_is_remote_error() -> None:
    with pytest.raises(RemoteProtocolError, match="JointFeedback") as info:
        decode_reply(Frame(15, 1, 0, bytes(131)), ByteOrder.LITTLE, Port.STATE)
    assert info.value.data == bytes(131)
    with pytest.raises(RemoteProtocolError):
        decode_reply(Frame(13, 1, 0, bytes(32)), ByteOrder.LITTLE, Port.STATE)


def test_unknown_type_is_a_value_not_an_error() -> None:
    f = Frame(2, 2, 0, b"\x01\x02")
    assert decode_request(f, ByteOrder.LITTLE, Port.MOTION) == UnknownMessage(2, b"\x01\x02")
    assert decode_reply(f, ByteOrder.LITTLE, Port.STATE) == UnknownMessage(2, b"\x01\x02")


@pytest.mark.parametrize(
    ("msg_type", "body", "port", "is_request", "expected"),
    [
        (2002, 60, Port.MOTION, False, "MotoMotionReply"),
        (2002, 60, Port.IO, False, "IoErrorReply"),
        (2012, 4, Port.IO, True, "MotoReadMRegister"),
        (2012, 8, Port.IO, False, "MotoReadMRegisterReply"),
        (2012, 4, Port.MOTION, True, "UnknownMessage"),
        (2013, 8, Port.IO, True, "MotoWriteMRegister"),
        (2013, 4, Port.IO, False, "MotoWriteMRegisterReply"),
        (2020, 0, Port.MOTION, True, "MotoGetDhParameters"),
        (2020, 512, Port.MOTION, False, "MotoGetDhParametersReply"),
        (1, 0, Port.MOTION, True, "Ping"),
        (1, 0, Port.MOTION, False, "PingReply"),
        (1, 0, Port.IO, True, "UnknownMessage"),
        (2003, 4, Port.MOTION, True, "MotoReadIoBit"),
        (2004, 8, Port.MOTION, False, "MotoReadIoBitReply"),
        (13, 28, Port.MOTION, True, "RobotStatus"),
        (2016, 8, Port.MOTION, True, "MotoJointTrajPtFullEx"),
        (2016, 8, Port.IO, True, "UnknownMessage"),
        (14, 136, Port.STATE, True, "UnknownMessage"),
    ],
)
def test_type_meaning_depends_on_port_and_direction(
    msg_type: int, body: int, port: Port, is_request: bool, expected: str
) -> None:
    decode = decode_request if is_request else decode_reply
    message = decode(Frame(msg_type, 2, 0, bytes(body)), ByteOrder.BIG, port)
    assert type(message).__name__ == expected


def test_full_ex_count_outside_range_is_kept() -> None:
    """n ≤ 0 carries no records but must reach the server, which answers it (§3.5)."""
    for n in (0, -5):
        body = struct.pack("<ii", n, 3)
        message = decode_request(Frame(2016, 2, 0, body), ByteOrder.LITTLE, Port.MOTION)
        assert message.number_of_valid_groups == n  # type: ignore[union-attr]
        assert message.groups == ()  # type: ignore[union-attr]


def test_feedback_ex_ignores_unused_slots_and_keeps_count() -> None:
    body = Body(LE, 532).i(0, 1).i(4, 0).i(8, 6).i(136, 1).bytes()  # slot 1 not zero: ignored
    message = decode_reply(Frame(2017, 1, 0, body), ByteOrder.LITTLE, Port.STATE)
    assert isinstance(message, MotoJointFeedbackEx)
    assert len(message.groups) == 1
    assert message.groups[0].valid_fields == 6


def test_decoded_integers_are_not_range_checked() -> None:
    """MotoROS accepts any int32; the server must see group 99 to answer 3004."""
    body = Body(LE, 60).i(0, 99).i(4, -7).i(8, 123456).i(12, 77).i(16, -1).bytes()
    message = decode_reply(Frame(2002, 3, 1, body), ByteOrder.LITTLE, Port.MOTION)
    assert message == MotoMotionReply(99, -7, 123456, 77, -1)


def test_decode_produces_plain_ints_and_tuples() -> None:
    body = Body(LE, 132).i(0, 1).i(4, 6).bytes()
    message = decode_reply(Frame(15, 1, 0, body), ByteOrder.LITTLE, Port.STATE)
    assert isinstance(message, JointFeedback)
    assert type(message.group_no) is int
    assert type(message.pos) is tuple
    assert len(message.pos) == 10
    status = decode_reply(Frame(13, 1, 0, bytes(28)), ByteOrder.LITTLE, Port.STATE)
    assert isinstance(status, RobotStatus)
    assert hash(status) == hash(RobotStatus(0, 0, 0, 0, 0, 0, 0))


def test_encode_frame_round_trips_raw_frames() -> None:
    f = Frame(9999, 0, 2, b"abc")
    decoder = FrameDecoder(ByteOrder.BIG)
    decoder.feed(encode_frame(f, ByteOrder.BIG))
    assert decoder.next_frame() == f


# ------------------------------------------------------------------ one-step decoding


@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_next_reply_at_every_split_matches_two_step(o: str) -> None:
    data, frames = _stream(o)
    order = ORDER_OF[o]
    expected = [decode_reply(f, order, Port.STATE) for f in frames]
    for cut in range(0, len(data) + 1, 7):
        decoder = FrameDecoder(order)
        got = []
        for chunk in (data[:cut], data[cut:]):
            decoder.feed(chunk)
            while (message := decoder.next_reply(Port.STATE)) is not None:
                got.append(message)
        assert got == expected, f"split at {cut}"


def test_next_reply_one_byte_at_a_time() -> None:
    data, frames = _stream(LE)
    decoder = FrameDecoder(ByteOrder.LITTLE)
    got = []
    for index in range(len(data)):
        decoder.feed(data[index : index + 1])
        message = decoder.next_reply(Port.STATE)
        if message is not None:
            got.append(message)
    assert got == [decode_reply(f, ByteOrder.LITTLE, Port.STATE) for f in frames]
    assert isinstance(got[-1], UnknownMessage)  # the ping reply is not a state message


def test_next_reply_port_decides_the_class() -> None:
    body = Body(LE, 60).i(0, 3).i(4, 3003).bytes()
    for port, expected in ((Port.IO, "IoErrorReply"), (Port.MOTION, "MotoMotionReply")):
        decoder = FrameDecoder(ByteOrder.LITTLE)
        decoder.feed(frame(LE, 2002, 3, 1, body))
        assert type(decoder.next_reply(port)).__name__ == expected


def test_next_request_decodes_requests() -> None:
    body = Body(BE, 12).i(0, 1).i(4, 5).i(8, 9).bytes()
    decoder = FrameDecoder(ByteOrder.BIG)
    decoder.feed(frame(BE, 2018, 2, 0, body) + frame(BE, 2012, 2, 0, bytes(4)))
    assert decoder.next_request(Port.MOTION) == MotoSelectTool(1, 5, 9)
    assert decoder.next_request(Port.MOTION) == UnknownMessage(2012, bytes(4))
    assert decoder.next_request(Port.MOTION) is None


def test_next_reply_bad_prefix_and_bad_size() -> None:
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(struct.pack("<i", 600))
    with pytest.raises(RemoteProtocolError, match="600"):
        decoder.next_reply(Port.STATE)
    decoder.discard()
    # a well-framed JOINT_FEEDBACK with a 4-byte body: consumed, then refused
    decoder.feed(frame(LE, 15, 1, 0, bytes(4)) + frame(LE, 13, 1, 0, bytes(28)))
    with pytest.raises(RemoteProtocolError, match="JointFeedback"):
        decoder.next_reply(Port.STATE)
    assert decoder.next_reply(Port.STATE) == RobotStatus(0, 0, 0, 0, 0, 0, 0)


@given(data=st.binary(max_size=700))
@settings(max_examples=300)
def test_next_reply_on_garbage_only_raises_remote_errors(data: bytes) -> None:
    decoder = FrameDecoder(ByteOrder.BIG)
    decoder.feed(data)
    for _ in range(len(data) // 16 + 1):  # bounded: each frame takes at least 16 bytes
        try:
            if decoder.next_reply(Port.STATE) is None:
                break
        except RemoteProtocolError:
            break
