"""Property tests: every message survives pack → unpack and encode → decode, both orders."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.protocol import (
    ByteOrder,
    DhLink,
    FrameDecoder,
    IoErrorReply,
    JointFeedback,
    JointTrajPtExData,
    JointTrajPtFull,
    Message,
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
    decode_reply,
    decode_request,
    encode,
)

f32 = st.floats(width=32, allow_nan=False, allow_infinity=False)
i32 = st.integers(-(2**31), 2**31 - 1)
u32 = st.integers(0, 2**32 - 1)
joints = st.tuples(*[f32] * 10)
orders = st.sampled_from([ByteOrder.LITTLE, ByteOrder.BIG])

feedback = st.builds(JointFeedback, i32, i32, f32, joints, joints, joints)
ex_data = st.builds(JointTrajPtExData, i32, i32, f32, joints, joints, joints)
dh_link = st.builds(DhLink, f32, f32, f32, f32)
dh_groups = st.tuples(*[st.tuples(*[dh_link] * 8)] * 4)

# (strategy, port, sent by a client?)
MESSAGES: dict[str, tuple[st.SearchStrategy[Message], Port, bool]] = {
    "ping": (st.just(Ping()), Port.MOTION, True),
    "ping-reply": (st.just(PingReply()), Port.MOTION, False),
    "status": (st.builds(RobotStatus, i32, i32, i32, i32, i32, i32, i32), Port.STATE, False),
    "traj": (
        st.builds(JointTrajPtFull, i32, i32, i32, f32, joints, joints, joints),
        Port.MOTION,
        True,
    ),
    "feedback": (feedback, Port.STATE, False),
    "ctrl": (st.builds(MotoMotionCtrl, i32, i32, i32, joints), Port.MOTION, True),
    "reply": (st.builds(MotoMotionReply, i32, i32, i32, i32, i32, joints), Port.MOTION, False),
    "full-ex": (
        st.builds(MotoJointTrajPtFullEx.for_groups, i32, st.lists(ex_data, max_size=4)),
        Port.MOTION,
        True,
    ),
    "feedback-ex": (
        st.builds(MotoJointFeedbackEx.for_groups, st.lists(feedback, max_size=4)),
        Port.STATE,
        False,
    ),
    "select-tool": (st.builds(MotoSelectTool, i32, i32, i32), Port.MOTION, True),
    "read-bit": (st.builds(MotoReadIoBit, u32), Port.IO, True),
    "read-bit-reply": (st.builds(MotoReadIoBitReply, u32, u32), Port.IO, False),
    "write-bit": (st.builds(MotoWriteIoBit, u32, u32), Port.MOTION, True),
    "write-bit-reply": (st.builds(MotoWriteIoBitReply, u32), Port.MOTION, False),
    "read-group": (st.builds(MotoReadIoGroup, u32), Port.IO, True),
    "read-group-reply": (st.builds(MotoReadIoGroupReply, u32, u32), Port.IO, False),
    "write-group": (st.builds(MotoWriteIoGroup, u32, u32), Port.IO, True),
    "write-group-reply": (st.builds(MotoWriteIoGroupReply, u32), Port.IO, False),
    "read-mreg": (st.builds(MotoReadMRegister, u32), Port.IO, True),
    "read-mreg-reply": (st.builds(MotoReadMRegisterReply, u32, u32), Port.IO, False),
    "write-mreg": (st.builds(MotoWriteMRegister, u32, u32), Port.IO, True),
    "write-mreg-reply": (st.builds(MotoWriteMRegisterReply, u32), Port.IO, False),
    "get-dh": (st.just(MotoGetDhParameters()), Port.MOTION, True),
    "get-dh-reply": (st.builds(MotoGetDhParametersReply, dh_groups), Port.MOTION, False),
    "io-error": (st.builds(IoErrorReply, i32, i32), Port.IO, False),
}

COVERED: dict[str, type[Message]] = {
    "ping": Ping,
    "ping-reply": PingReply,
    "status": RobotStatus,
    "traj": JointTrajPtFull,
    "feedback": JointFeedback,
    "ctrl": MotoMotionCtrl,
    "reply": MotoMotionReply,
    "full-ex": MotoJointTrajPtFullEx,
    "feedback-ex": MotoJointFeedbackEx,
    "select-tool": MotoSelectTool,
    "read-bit": MotoReadIoBit,
    "read-bit-reply": MotoReadIoBitReply,
    "write-bit": MotoWriteIoBit,
    "write-bit-reply": MotoWriteIoBitReply,
    "read-group": MotoReadIoGroup,
    "read-group-reply": MotoReadIoGroupReply,
    "write-group": MotoWriteIoGroup,
    "write-group-reply": MotoWriteIoGroupReply,
    "read-mreg": MotoReadMRegister,
    "read-mreg-reply": MotoReadMRegisterReply,
    "write-mreg": MotoWriteMRegister,
    "write-mreg-reply": MotoWriteMRegisterReply,
    "get-dh": MotoGetDhParameters,
    "get-dh-reply": MotoGetDhParametersReply,
    "io-error": IoErrorReply,
}


def each_message(test: Callable[..., None]) -> Callable[..., None]:
    """``test`` for every message of MESSAGES, 40 drawn in either byte order."""
    test = settings(max_examples=40)(test)
    test = given(data=st.data(), order=orders)(test)
    return pytest.mark.parametrize("name", sorted(MESSAGES))(test)


@each_message
def test_body_round_trip(name: str, data: st.DataObject, order: ByteOrder) -> None:
    strategy, _port, _request = MESSAGES[name]
    message = data.draw(strategy)
    body = message.pack(order)
    assert len(body) == type(message).BODY_SIZE or isinstance(message, MotoJointTrajPtFullEx)
    assert type(message).unpack(body, order) == message


@each_message
def test_frame_round_trip(name: str, data: st.DataObject, order: ByteOrder) -> None:
    strategy, port, request = MESSAGES[name]
    message = data.draw(strategy)
    decoder = FrameDecoder(order)
    decoder.feed(encode(message, order))
    frame = decoder.next_frame()
    assert frame is not None
    assert decoder.buffered == 0
    decode = decode_request if request else decode_reply
    assert decode(frame, order, port) == message


def test_every_message_class_is_covered() -> None:
    """A new message class must get a strategy above."""
    import pymotoros.protocol.messages as messages

    classes = {
        obj
        for obj in vars(messages).values()
        if isinstance(obj, type) and issubclass(obj, Message) and obj is not Message
    }
    covered = {COVERED[name] for name in MESSAGES}
    assert classes - covered == {JointTrajPtExData}  # only ever inside FULL_EX


@pytest.mark.parametrize("name", sorted(MESSAGES))
@given(data=st.data())
@settings(max_examples=5)
def test_strategy_builds_the_named_class(name: str, data: st.DataObject) -> None:
    assert type(data.draw(MESSAGES[name][0])) is COVERED[name]


@given(st.lists(st.floats(width=32, allow_nan=False, allow_infinity=False), max_size=10))
def test_for_joints_pads_to_ten(values: list[float]) -> None:
    point = JointTrajPtFull.for_joints(0, 1, 0.5, values, values)
    assert point.pos[: len(values)] == tuple(values)
    assert point.pos[len(values) :] == (0.0,) * (10 - len(values))
    assert point.valid_fields == 7
    assert len(point.acc) == 10
