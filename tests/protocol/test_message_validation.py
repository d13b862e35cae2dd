"""Construction refuses what cannot go on the wire; decoding never builds such a thing."""

from __future__ import annotations

import pytest

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol import (
    ByteOrder,
    JointFeedback,
    JointTrajPtExData,
    JointTrajPtFull,
    MotoGetDhParametersReply,
    MotoJointFeedbackEx,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoReadIoBit,
    MotoSelectTool,
    MotoWriteIoBitReply,
    MotoWriteIoGroup,
    MotoWriteIoGroupReply,
    Ping,
    PingReply,
    UnknownMessage,
    encode,
)

ZEROS = (0.0,) * 10


@pytest.mark.parametrize("length", [0, 9, 11])
def test_arrays_must_have_ten_values(length: int) -> None:
    with pytest.raises(LocalProtocolError, match="pos"):
        JointTrajPtFull(0, 0, 7, 0.0, (0.0,) * length, ZEROS, ZEROS)


@pytest.mark.parametrize("value", [2**31, -(2**31) - 1])
def test_int32_range(value: int) -> None:
    with pytest.raises(LocalProtocolError, match="int32"):
        MotoSelectTool(0, value, 1)
    MotoSelectTool(0, 2**31 - 1, -(2**31))  # the extremes fit


@pytest.mark.parametrize("value", [-1, 2**32])
def test_uint32_range(value: int) -> None:
    with pytest.raises(LocalProtocolError, match="uint32"):
        MotoReadIoBit(value)
    with pytest.raises(LocalProtocolError, match="uint32"):
        MotoWriteIoGroup(10, value)
    MotoReadIoBit(2**32 - 1)


def test_non_int_field() -> None:
    with pytest.raises(LocalProtocolError, match="int"):
        MotoMotionCtrl(0, 1.5, 200101)  # type: ignore[arg-type]


def test_float32_overflow() -> None:
    with pytest.raises(LocalProtocolError, match="float32"):
        JointTrajPtFull.for_joints(0, 0, 1e39, [0.0], [0.0])
    with pytest.raises(LocalProtocolError, match="float"):
        JointTrajPtFull.for_joints(0, 0, 0.0, ["x"], [0.0])  # type: ignore[list-item]


def test_local_error_is_a_value_error() -> None:
    with pytest.raises(ValueError, match="values"):
        JointFeedback.for_joints(0, [0.0] * 11)


def test_lists_are_stored_as_tuples() -> None:
    point = JointTrajPtFull(0, 0, 7, 0.0, [1.0] * 10, ZEROS, ZEROS)  # type: ignore[arg-type]
    assert point.pos == (1.0,) * 10
    assert isinstance(point.pos, tuple)
    hash(point)


def test_messages_are_frozen() -> None:
    point = JointTrajPtFull.for_joints(0, 0, 0.0, [], [])
    with pytest.raises(AttributeError):
        point.sequence = 3  # type: ignore[misc]
    with pytest.raises(AttributeError):
        point.extra = 1  # type: ignore[attr-defined]


def test_equality_is_typed() -> None:
    """Messages are tuples underneath; equality must still tell the types apart."""
    assert Ping() != PingReply()
    assert MotoWriteIoBitReply(0) != MotoWriteIoGroupReply(0)
    assert MotoWriteIoBitReply(0) != (0,)
    assert MotoWriteIoBitReply(0) == MotoWriteIoBitReply(0)
    assert len({MotoWriteIoBitReply(0), MotoWriteIoBitReply(0)}) == 1
    assert bool(Ping())  # an empty body is still a message


def test_replace_and_asdict() -> None:
    point = JointTrajPtFull.for_joints(0, 0, 0.5, [1.0], [])
    later = point._replace(sequence=4)
    assert type(later) is JointTrajPtFull
    assert later.sequence == 4
    assert point._asdict()["time"] == 0.5


def test_full_ex_count_must_match_records() -> None:
    record = JointTrajPtExData.for_joints(0, 0.5, [0.1], [0.0])
    with pytest.raises(LocalProtocolError, match="records"):
        MotoJointTrajPtFullEx(2, 1, (record,))
    with pytest.raises(LocalProtocolError, match="at most 4"):
        MotoJointTrajPtFullEx.for_groups(1, [record] * 5)
    with pytest.raises(LocalProtocolError, match="JointTrajPtExData"):
        MotoJointTrajPtFullEx(1, 1, (JointFeedback.for_joints(0, []),))  # type: ignore[arg-type]
    ex = MotoJointTrajPtFullEx.for_groups(1, [record, record])
    assert ex.number_of_valid_groups == 2
    assert len(encode(ex, ByteOrder.LITTLE)) == 24 + 2 * 132


def test_feedback_ex_count_must_match_records() -> None:
    record = JointFeedback.for_joints(0, [0.1], [0.0])
    with pytest.raises(LocalProtocolError, match="records"):
        MotoJointFeedbackEx(3, (record,))
    assert len(encode(MotoJointFeedbackEx.for_groups([record]), ByteOrder.BIG)) == 548


def test_dh_reply_shape() -> None:
    with pytest.raises(LocalProtocolError, match="groups"):
        MotoGetDhParametersReply(((),))
    with pytest.raises(LocalProtocolError, match="links"):
        MotoGetDhParametersReply.for_groups([[(0.0, 0.0, 0.0, 0.0)] * 9])


def test_for_joints_flags() -> None:
    assert JointTrajPtFull.for_joints(0, 0, 0.0, [], []).valid_fields == 7
    assert JointTrajPtFull.for_joints(0, 0, 0.0, [], [], [1.0]).valid_fields == 15
    assert JointFeedback.for_joints(0, [1.0]).valid_fields == 2
    assert JointFeedback.for_joints(0, [1.0], [0.0]).valid_fields == 6
    assert JointTrajPtFull.for_joints(0, 0, 0.0, [], [], valid_fields=3).valid_fields == 3


def test_unknown_message_range() -> None:
    with pytest.raises(LocalProtocolError):
        UnknownMessage(2**31)
    assert UnknownMessage(2, bytearray(b"ab")).body == b"ab"


def test_oversized_unknown_message_cannot_be_encoded() -> None:
    with pytest.raises(LocalProtocolError, match="552"):
        encode(UnknownMessage(7, bytes(537)), ByteOrder.LITTLE)
    assert len(encode(UnknownMessage(7, bytes(536)), ByteOrder.LITTLE)) == 552


def test_header_values_out_of_range() -> None:
    with pytest.raises(LocalProtocolError):
        encode(UnknownMessage(7), ByteOrder.LITTLE, comm_type=2**32)
