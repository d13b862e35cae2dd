"""Golden frames: every message of reference §1.3/§1.4, both byte orders.

The expected bytes are assembled by hand in :mod:`sm_wire` from the offset
tables (never by calling the codec); each case also states the total size from
the §1.3 catalogue. Each case is checked three ways: ``encode`` produces the
bytes, ``FrameDecoder`` + ``decode_*`` turns the bytes back into an equal
message, and the size matches the catalogue.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import pytest
from sm_wire import ORDERS, Body, frame, pad10

from pymotoros.protocol import (
    ByteOrder,
    DhLink,
    FrameDecoder,
    IoErrorReply,
    JointFeedback,
    JointTrajPtExData,
    JointTrajPtFull,
    MotoGetDhParameters,
    MotoGetDhParametersReply,
    MotoJointFeedbackEx,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
    MotoReadIoGroup,
    MotoReadIoGroupReply,
    MotoReadMRegister,
    MotoReadMRegisterReply,
    MotoSelectTool,
    MotoWriteIoBit,
    MotoWriteIoBitReply,
    MotoWriteIoGroup,
    MotoWriteIoGroupReply,
    MotoWriteMRegister,
    MotoWriteMRegisterReply,
    Ping,
    PingReply,
    Port,
    RobotStatus,
    UnknownMessage,
    WireMessage,
    decode_reply,
    decode_request,
    encode,
    header_problem,
)

# header codes, literally (§1.2)
REQ, REP, TOPIC = 2, 3, 1
NONE, OK, FAIL = 0, 1, 2

POS = (0.5, -1.25, 2.0, 0.125, -3.5, 4.0, 0.0, 1.5)
VEL = (0.25, 0.5, -0.75, 1.0, 0.0, -2.0)
ACC = (8.0, -8.0)


@dataclass(frozen=True)
class Case:
    name: str
    message: WireMessage
    port: Port
    request: bool
    total: int
    """Bytes on the wire, from the §1.3 catalogue."""
    build: Callable[[str], bytes]


def _ctrl(o: str) -> bytes:
    body = Body(o, 52).i(0, 1).i(4, 7).i(8, 200121).fs(12, (1.0, 2.0))
    return frame(o, 2001, REQ, NONE, body.bytes())


def _reply(o: str) -> bytes:
    body = Body(o, 60).i(0, -1).i(4, 42).i(8, 14).i(12, 5).i(16, 5006)
    return frame(o, 2002, REP, OK, body.bytes())


def _traj(o: str) -> bytes:
    body = Body(o, 136).i(0, 1).i(4, 3).i(8, 7).f(12, 0.75)
    body.fs(16, POS).fs(56, VEL).fs(96, ACC)
    return frame(o, 14, REQ, NONE, body.bytes())


def _feedback(o: str) -> bytes:
    body = Body(o, 132).i(0, 2).i(4, 6).f(8, 0.0).fs(12, POS).fs(52, VEL)
    return frame(o, 15, TOPIC, NONE, body.bytes())


def _status(o: str) -> bytes:
    body = Body(o, 28)
    for k, value in enumerate((1, 0, 4107, 1, -1, 2, 1)):
        body.i(4 * k, value)
    return frame(o, 13, TOPIC, NONE, body.bytes())


def _full_ex(n: int) -> Callable[[str], bytes]:
    def build(o: str) -> bytes:
        body = Body(o, 8 + 132 * n).i(0, n).i(4, 9)
        for g in range(n):
            body.record(8 + 132 * g, g, 7, 0.5 * (g + 1), POS[: g + 2], VEL[:g], ())
        return frame(o, 2016, REQ, NONE, body.bytes())

    return build


def _full_ex_message(n: int) -> MotoJointTrajPtFullEx:
    return MotoJointTrajPtFullEx(
        n,
        9,
        tuple(
            JointTrajPtExData(g, 7, 0.5 * (g + 1), pad10(POS[: g + 2]), pad10(VEL[:g]), pad10(()))
            for g in range(n)
        ),
    )


def _feedback_ex(o: str) -> bytes:
    body = Body(o, 532).i(0, 2)
    body.record(4, 0, 6, 0.0, POS, VEL, ())
    body.record(136, 1, 2, 0.0, (1.0, 2.0), (), ())
    return frame(o, 2017, TOPIC, NONE, body.bytes())


def _io(msg_type: int, comm: int, reply: int, *values: int) -> Callable[[str], bytes]:
    def build(o: str) -> bytes:
        body = Body(o, 4 * len(values))
        for k, value in enumerate(values):
            body.u(4 * k, value)
        return frame(o, msg_type, comm, reply, body.bytes())

    return build


DH_GROUPS = ((1.0, 0.5, 0.25, -1.5), (0.0, 0.125, 2.0, 1.5))


def _dh_reply(o: str) -> bytes:
    body = Body(o, 512)
    # group 1, links 0 and 1 (theta, d, a, alpha); every other group and link is zero
    for link, params in enumerate(DH_GROUPS):
        body.fs(((1 * 8 + link) * 4) * 4, params)
    return frame(o, 2020, REP, OK, body.bytes())


def _io_error(o: str) -> bytes:
    return frame(o, 2002, REP, OK, Body(o, 60).i(0, 3).i(4, 3001).bytes())


CASES = [
    Case("ping", Ping(), Port.MOTION, True, 16, lambda o: frame(o, 1, REQ, NONE)),
    Case("ping-reply", PingReply(), Port.MOTION, False, 16, lambda o: frame(o, 1, REP, OK)),
    Case("robot-status", RobotStatus(1, 0, 4107, 1, -1, 2, 1), Port.STATE, False, 44, _status),
    Case(
        "joint-traj-pt-full",
        JointTrajPtFull(1, 3, 7, 0.75, pad10(POS), pad10(VEL), pad10(ACC)),
        Port.MOTION,
        True,
        152,
        _traj,
    ),
    Case(
        "joint-feedback",
        JointFeedback(2, 6, 0.0, pad10(POS), pad10(VEL), pad10(())),
        Port.STATE,
        False,
        148,
        _feedback,
    ),
    Case(
        "motion-ctrl",
        MotoMotionCtrl(1, 7, 200121, pad10((1.0, 2.0))),
        Port.MOTION,
        True,
        68,
        _ctrl,
    ),
    Case("motion-reply", MotoMotionReply(-1, 42, 14, 5, 5006), Port.MOTION, False, 76, _reply),
    Case("full-ex-1", _full_ex_message(1), Port.MOTION, True, 24 + 132, _full_ex(1)),
    Case("full-ex-2", _full_ex_message(2), Port.MOTION, True, 24 + 264, _full_ex(2)),
    Case("full-ex-4", _full_ex_message(4), Port.MOTION, True, 552, _full_ex(4)),
    Case(
        "feedback-ex",
        MotoJointFeedbackEx(
            2,
            (
                JointFeedback(0, 6, 0.0, pad10(POS), pad10(VEL), pad10(())),
                JointFeedback(1, 2, 0.0, pad10((1.0, 2.0)), pad10(()), pad10(())),
            ),
        ),
        Port.STATE,
        False,
        548,
        _feedback_ex,
    ),
    Case(
        "select-tool",
        MotoSelectTool(group_no=1, tool=5, sequence=77),
        Port.MOTION,
        True,
        28,
        lambda o: frame(o, 2018, REQ, NONE, Body(o, 12).i(0, 1).i(4, 5).i(8, 77).bytes()),
    ),
    Case(
        "read-bit",
        MotoReadIoBit(4_000_000_000),
        Port.IO,
        True,
        20,
        _io(2003, REQ, NONE, 4_000_000_000),
    ),
    Case("read-bit-reply", MotoReadIoBitReply(1, 0), Port.IO, False, 24, _io(2004, REP, OK, 1, 0)),
    Case(
        "read-bit-reply-fail",
        MotoReadIoBitReply(0, 1001),
        Port.IO,
        False,
        24,
        _io(2004, REP, FAIL, 0, 1001),
    ),
    Case(
        "write-bit", MotoWriteIoBit(10010, 1), Port.MOTION, True, 24, _io(2005, REQ, NONE, 10010, 1)
    ),
    Case(
        "write-bit-reply", MotoWriteIoBitReply(1003), Port.IO, False, 20, _io(2006, REP, FAIL, 1003)
    ),
    Case("read-group", MotoReadIoGroup(1001), Port.IO, True, 20, _io(2007, REQ, NONE, 1001)),
    Case(
        "read-group-reply",
        MotoReadIoGroupReply(0xA5, 0),
        Port.MOTION,
        False,
        24,
        _io(2008, REP, OK, 0xA5, 0),
    ),
    Case(
        "write-group",
        MotoWriteIoGroup(1001, 0xFF),
        Port.IO,
        True,
        24,
        _io(2009, REQ, NONE, 1001, 0xFF),
    ),
    Case("write-group-reply", MotoWriteIoGroupReply(0), Port.IO, False, 20, _io(2010, REP, OK, 0)),
    Case("read-mreg", MotoReadMRegister(1000123), Port.IO, True, 20, _io(2012, REQ, NONE, 1000123)),
    Case(
        "read-mreg-reply",
        MotoReadMRegisterReply(0xFFFF, 0),
        Port.IO,
        False,
        24,
        _io(2012, REP, OK, 0xFFFF, 0),
    ),
    Case(
        "write-mreg",
        MotoWriteMRegister(559, 65535),
        Port.IO,
        True,
        24,
        _io(2013, REQ, NONE, 559, 65535),
    ),
    Case(
        "write-mreg-reply",
        MotoWriteMRegisterReply(1002),
        Port.IO,
        False,
        20,
        _io(2013, REP, FAIL, 1002),
    ),
    Case(
        "get-dh", MotoGetDhParameters(), Port.MOTION, True, 16, lambda o: frame(o, 2020, REQ, NONE)
    ),
    Case(
        "get-dh-reply",
        MotoGetDhParametersReply.for_groups(((), DH_GROUPS)),
        Port.MOTION,
        False,
        528,
        _dh_reply,
    ),
    Case("io-error-reply", IoErrorReply(3, 3001), Port.IO, False, 76, _io_error),
]

ORDER_OF = {"<": ByteOrder.LITTLE, ">": ByteOrder.BIG}


def _decode(case: Case, data: bytes, order: ByteOrder) -> WireMessage:
    decoder = FrameDecoder(order)
    decoder.feed(data)
    frame_ = decoder.next_frame()
    assert frame_ is not None
    assert decoder.next_frame() is None
    if case.request:
        return decode_request(frame_, order, case.port)
    return decode_reply(frame_, order, case.port)


@pytest.mark.parametrize("o", ORDERS, ids=["le", "be"])
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_encode_matches_hand_built_bytes(case: Case, o: str) -> None:
    expected = case.build(o)
    assert len(expected) == case.total
    assert encode(case.message, ORDER_OF[o]) == expected


@pytest.mark.parametrize("o", ORDERS, ids=["le", "be"])
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_hand_built_bytes_decode_to_the_message(case: Case, o: str) -> None:
    decoded = _decode(case, case.build(o), ORDER_OF[o])
    assert type(decoded) is type(case.message)
    assert decoded == case.message


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_default_headers_pass_the_ros_driver_checks(case: Case) -> None:
    data = encode(case.message, ByteOrder.LITTLE)
    decoder = FrameDecoder(ByteOrder.LITTLE)
    decoder.feed(data)
    frame_ = decoder.next_frame()
    assert frame_ is not None
    assert header_problem(frame_) is None


def test_little_endian_literal_motion_ctrl() -> None:
    """START_TRAJ_MODE for group 1, sequence 7, typed out byte by byte (200121 = 0x00030DB9)."""
    expected = bytes.fromhex(
        "40000000"
        "d1070000"
        "02000000"
        "00000000"  # prefix 64, type 2001, request, invalid
        "01000000"
        "07000000"
        "b90d0300"  # groupNo, sequence, command
    ) + bytes(40)
    assert encode(MotoMotionCtrl(1, 7, 200121), ByteOrder.LITTLE) == expected


def test_big_endian_literal_motion_ctrl() -> None:
    expected = bytes.fromhex("00000040000007d10000000200000000000000010000000700030db9") + bytes(40)
    assert encode(MotoMotionCtrl(1, 7, 200121), ByteOrder.BIG) == expected


def test_literal_ping_reply_both_orders() -> None:
    assert encode(PingReply(), ByteOrder.LITTLE) == bytes.fromhex(
        "0c000000010000000300000001000000"
    )
    assert encode(PingReply(), ByteOrder.BIG) == bytes.fromhex("0000000c000000010000000300000001")


def test_float_one_is_ieee754_single() -> None:
    """time = 1.0 s is 0x3F800000 at body offset 12 of JOINT_TRAJ_PT_FULL."""
    point = JointTrajPtFull.for_joints(0, 0, 1.0, [], [])
    le = encode(point, ByteOrder.LITTLE)
    be = encode(point, ByteOrder.BIG)
    assert le[16 + 12 : 16 + 16] == bytes.fromhex("0000803f")
    assert be[16 + 12 : 16 + 16] == bytes.fromhex("3f800000")


@pytest.mark.parametrize("o", ORDERS, ids=["le", "be"])
def test_unknown_message_encodes_raw(o: str) -> None:
    """GET_VERSION (2) is defined but unhandled; tools send it as a raw request."""
    assert encode(UnknownMessage(2), ORDER_OF[o]) == frame(o, 2, REQ, NONE)


@pytest.mark.parametrize("o", ORDERS, ids=["le", "be"])
def test_header_overrides(o: str) -> None:
    order = ORDER_OF[o]
    assert encode(MotoWriteIoBitReply(0), order, reply_type=2) == frame(
        o, 2006, REP, FAIL, Body(o, 4).bytes()
    )
    assert encode(Ping(), order, comm_type=3, reply_type=1) == frame(o, 1, REP, OK)


def test_dh_links_are_named() -> None:
    reply = MotoGetDhParametersReply.for_groups(((), DH_GROUPS))
    assert reply.groups[1][0] == DhLink(theta=1.0, d=0.5, a=0.25, alpha=-1.5)
    assert reply.groups[0] == (DhLink(0.0, 0.0, 0.0, 0.0),) * 8
    assert len(reply.groups) == 4
