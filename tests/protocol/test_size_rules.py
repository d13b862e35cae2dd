"""The size-by-type rules of reference §1.5, row by row, and the error replies they give."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sm_wire import BE, LE, Body, frame

from pymotoros.protocol import (
    ByteOrder,
    Frame,
    IoErrorReply,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadMRegister,
    Port,
    encode,
)
from pymotoros.protocol.framing import REQUEST_CLASSES
from pymotoros.protocol.sizes import (
    IO_SIZES,
    MOTION_SIZES,
    Accept,
    Close,
    Reject,
    check_request,
    expected_size,
)

ORDER_OF = {LE: ByteOrder.LITTLE, BE: ByteOrder.BIG}

# §1.5, first list: total sizes the motion-port receive task expects
MOTION_TABLE = [
    (1, 16),
    (13, 44),
    (14, 152),
    (15, 148),
    (2001, 68),
    (2002, 76),
    (2017, 548),
    (2003, 20),
    (2005, 24),
    (2007, 20),
    (2009, 24),
    (2020, 16),
    (2018, 28),
]
MOTION_UNKNOWN = [2, 2004, 2006, 2008, 2010, 2011, 2012, 2013, 2014, 2015, 2019, 0, -1, 3]
IO_TABLE = [(2003, 20), (2005, 24), (2007, 20), (2009, 24), (2012, 20), (2013, 24)]
IO_UNKNOWN = [1, 2, 13, 14, 15, 2001, 2002, 2004, 2016, 2017, 2018, 2020]
CLOSE_ON_MOTION = {13, 15, 2002, 2017}
ECHO_TYPES = {2001, 14, 2016, 2018}


@pytest.mark.parametrize(("msg_type", "total"), MOTION_TABLE)
def test_motion_table_row(msg_type: int, total: int) -> None:
    assert expected_size(msg_type, Port.MOTION, b"", ByteOrder.LITTLE) == total


@pytest.mark.parametrize(("msg_type", "total"), IO_TABLE)
def test_io_table_row(msg_type: int, total: int) -> None:
    assert expected_size(msg_type, Port.IO, b"", ByteOrder.LITTLE) == total


def test_tables_have_no_extra_rows() -> None:
    assert dict(MOTION_SIZES) == dict(MOTION_TABLE)
    assert dict(IO_SIZES) == dict(IO_TABLE)


def test_every_sized_type_has_a_request_class() -> None:
    assert set(MOTION_SIZES) | {2016} == set(REQUEST_CLASSES[Port.MOTION])
    assert set(IO_SIZES) == set(REQUEST_CLASSES[Port.IO])


@pytest.mark.parametrize(("n", "total"), [(1, 156), (2, 288), (3, 420), (4, 552), (5, 684)])
@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_full_ex_size_from_n(o: str, n: int, total: int) -> None:
    body = struct.pack(o + "ii", n, 0)
    assert expected_size(2016, Port.MOTION, body, ORDER_OF[o]) == total


def test_full_ex_without_n_expects_552() -> None:
    """Fewer than 20 bytes on the wire: n is not there, MotoROS assumes the full size."""
    assert expected_size(2016, Port.MOTION, b"\x01\x00\x00", ByteOrder.LITTLE) == 552
    assert expected_size(2016, Port.MOTION, b"\x01\x00\x00\x00", ByteOrder.LITTLE) == 156


def test_state_port_reads_nothing() -> None:
    with pytest.raises(ValueError, match="state"):
        check_request(Frame(1, 2, 0, b""), ByteOrder.LITTLE, Port.STATE)


# ------------------------------------------------------------------ unknown type: 3003


@pytest.mark.parametrize("msg_type", MOTION_UNKNOWN)
def test_unknown_on_motion_port(msg_type: int) -> None:
    verdict = check_request(Frame(msg_type, 2, 0, bytes(8)), ByteOrder.LITTLE, Port.MOTION)
    assert verdict == Reject(MotoMotionReply(-1, -1, msg_type, 3, 3003), 3003)


@pytest.mark.parametrize("msg_type", IO_UNKNOWN)
def test_unknown_on_io_port(msg_type: int) -> None:
    verdict = check_request(Frame(msg_type, 2, 0, bytes(136)), ByteOrder.LITTLE, Port.IO)
    assert verdict == Reject(IoErrorReply(3, 3003), 3003)


@pytest.mark.parametrize("o", [LE, BE], ids=["le", "be"])
def test_io_error_reply_bytes(o: str) -> None:
    verdict = check_request(Frame(2001, 2, 0, bytes(52)), ORDER_OF[o], Port.IO)
    assert isinstance(verdict, Reject)
    expected = frame(o, 2002, 3, 1, Body(o, 60).i(0, 3).i(4, 3003).bytes())
    assert encode(verdict.reply, ORDER_OF[o]) == expected


# ------------------------------------------------------------------ short: 3001


@pytest.mark.parametrize(("msg_type", "total"), [r for r in MOTION_TABLE if r[1] > 16])
def test_short_on_motion_port(msg_type: int, total: int) -> None:
    body_size = total - 16
    verdict = check_request(
        Frame(msg_type, 2, 0, bytes(body_size - 1)), ByteOrder.LITTLE, Port.MOTION
    )
    assert isinstance(verdict, Reject)
    assert verdict.subcode == 3001
    if msg_type in ECHO_TYPES:
        assert verdict.reply.group_no == 0  # type: ignore[union-attr]
    else:
        assert verdict.reply == MotoMotionReply(-1, -1, msg_type, 3, 3001)


@pytest.mark.parametrize(("msg_type", "total"), IO_TABLE)
def test_short_on_io_port(msg_type: int, total: int) -> None:
    verdict = check_request(Frame(msg_type, 2, 0, bytes(total - 17)), ByteOrder.LITTLE, Port.IO)
    assert verdict == Reject(IoErrorReply(3, 3001), 3001)


@pytest.mark.parametrize(
    ("o", "command"),
    [(LE, 0x0DB9), (BE, 0x00030000)],  # 200121 = 0x00030DB9, two bytes arrive, rest zero
    ids=["le", "be"],
)
def test_short_motion_ctrl_echoes_sequence_and_partial_command(o: str, command: int) -> None:
    body = Body(o, 12).i(0, 3).i(4, 5).i(8, 200121).bytes()[:10]
    verdict = check_request(Frame(2001, 2, 0, body), ORDER_OF[o], Port.MOTION)
    assert verdict == Reject(MotoMotionReply(0, 5, command, 3, 3001), 3001)


@pytest.mark.parametrize(
    ("msg_type", "body", "sequence"),
    [
        (14, struct.pack("<iii", 2, 44, 7), 44),
        (2016, struct.pack("<ii", 2, 45), 45),  # n = 2 but no records
        (2016, struct.pack("<i", 1), 0),  # n present, sequence missing
        (2016, b"\x01\x00", 0),  # not even n: 552 expected
        (2018, struct.pack("<ii", 1, 5), 0),  # groupNo, tool; sequence missing
        (2018, struct.pack("<iii", 1, 5, 46)[:11], 46 & 0xFFFF),
    ],
)
def test_short_echo_types(msg_type: int, body: bytes, sequence: int) -> None:
    verdict = check_request(Frame(msg_type, 2, 0, body), ByteOrder.LITTLE, Port.MOTION)
    assert verdict == Reject(MotoMotionReply(0, sequence, msg_type, 3, 3001), 3001)


def test_full_ex_with_too_many_groups_is_short() -> None:
    body = struct.pack("<ii", 5, 8) + bytes(528)
    verdict = check_request(Frame(2016, 2, 0, body), ByteOrder.LITTLE, Port.MOTION)
    assert verdict == Reject(MotoMotionReply(0, 8, 2016, 3, 3001), 3001)


# ------------------------------------------------------------------ close


@pytest.mark.parametrize(
    ("msg_type", "total"), [r for r in MOTION_TABLE if r[0] in CLOSE_ON_MOTION]
)
def test_state_types_on_motion_port_close(msg_type: int, total: int) -> None:
    verdict = check_request(Frame(msg_type, 1, 0, bytes(total - 16)), ByteOrder.LITTLE, Port.MOTION)
    assert isinstance(verdict, Close)
    assert verdict.msg_type == msg_type


def test_short_state_type_gets_3001_before_close() -> None:
    verdict = check_request(Frame(13, 1, 0, bytes(4)), ByteOrder.LITTLE, Port.MOTION)
    assert verdict == Reject(MotoMotionReply(-1, -1, 13, 3, 3001), 3001)


# ------------------------------------------------------------------ accept


@pytest.mark.parametrize(
    ("msg_type", "total"), [r for r in MOTION_TABLE if r[0] not in CLOSE_ON_MOTION]
)
def test_exact_size_is_accepted_on_motion_port(msg_type: int, total: int) -> None:
    verdict = check_request(Frame(msg_type, 2, 0, bytes(total - 16)), ByteOrder.LITTLE, Port.MOTION)
    assert isinstance(verdict, Accept)
    assert int(verdict.message.MSG_TYPE) == msg_type
    assert verdict.surplus == 0
    assert verdict.reply_expected


@pytest.mark.parametrize(("msg_type", "total"), IO_TABLE)
def test_exact_size_is_accepted_on_io_port(msg_type: int, total: int) -> None:
    verdict = check_request(Frame(msg_type, 3, 1, bytes(total - 16)), ByteOrder.LITTLE, Port.IO)
    assert isinstance(verdict, Accept)
    assert verdict.reply_expected  # the IO port always answers, whatever the comm type


def test_longer_body_processes_the_first_message() -> None:
    body = encode(MotoMotionCtrl(0, 4, 200101), ByteOrder.LITTLE)[16:] + b"\xff" * 8
    verdict = check_request(Frame(2001, 2, 0, body), ByteOrder.LITTLE, Port.MOTION)
    assert verdict == Accept(MotoMotionCtrl(0, 4, 200101), surplus=8)


def test_full_ex_padded_to_552_is_accepted() -> None:
    body = Body(LE, 536).i(0, 2).i(4, 9).i(8, 0).i(12, 7).i(140, 1).i(144, 7).bytes()
    verdict = check_request(Frame(2016, 2, 0, body), ByteOrder.LITTLE, Port.MOTION)
    assert isinstance(verdict, Accept)
    assert verdict.surplus == 2 * 132
    message = verdict.message
    assert isinstance(message, MotoJointTrajPtFullEx)
    assert message.sequence == 9
    assert [g.group_no for g in message.groups] == [0, 1]


@pytest.mark.parametrize("n", [0, -1, -1000])
def test_full_ex_without_groups_reaches_the_server(n: int) -> None:
    body = struct.pack("<ii", n, 3)
    verdict = check_request(Frame(2016, 2, 0, body), ByteOrder.LITTLE, Port.MOTION)
    assert verdict == Accept(MotoJointTrajPtFullEx(n, 3, ()))


def test_service_reply_on_motion_port_is_processed_silently() -> None:
    verdict = check_request(Frame(2001, 3, 1, bytes(52)), ByteOrder.LITTLE, Port.MOTION)
    assert isinstance(verdict, Accept)
    assert not verdict.reply_expected


def test_mregister_accepted_on_io_port_only() -> None:
    f = Frame(2012, 2, 0, struct.pack("<I", 1000005))
    assert check_request(f, ByteOrder.LITTLE, Port.IO) == Accept(MotoReadMRegister(1000005))
    assert isinstance(check_request(f, ByteOrder.LITTLE, Port.MOTION), Reject)


@given(
    msg_type=st.sampled_from([1, 2, 13, 14, 15, 2001, 2002, 2003, 2005, 2012, 2016, 2017, 2018]),
    body=st.binary(max_size=536),
    port=st.sampled_from([Port.MOTION, Port.IO]),
    comm=st.integers(-5, 5),
)
@settings(max_examples=400)
def test_check_request_never_raises(msg_type: int, body: bytes, port: Port, comm: int) -> None:
    verdict = check_request(Frame(msg_type, comm, 0, body), ByteOrder.BIG, port)
    assert isinstance(verdict, Accept | Reject | Close)
