"""The message registry: classes declare type, ports and size once; everything else follows.

Each class says ``MSG_TYPE``, ``REQUEST_ON`` / ``REPLY_ON`` and its layout, and
registers itself when defined. These tests pin the result against the
reference tables (§1.3–§1.6) written out here by hand, so a class that forgets
a port, lands on a wrong one or changes size fails here, not on a robot.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_message_roundtrip import COVERED, MESSAGES

from pymotoros.client.connection import expected_echo
from pymotoros.protocol import (
    ByteOrder,
    FrameDecoder,
    Message,
    MsgType,
    Port,
    encode,
)
from pymotoros.protocol import messages as messages_package
from pymotoros.protocol.framing import FRAME_OVERHEAD
from pymotoros.protocol.messages import (
    BODY_SIZE_DH_REPLY,
    BODY_SIZE_FEEDBACK_EX,
    BODY_SIZE_FULL_EX_HEAD,
    BODY_SIZE_GROUP_RECORD,
    BODY_SIZE_MOTION_REPLY,
    BODY_SIZE_TRAJ_PT_FULL,
    REPLY_CLASSES,
    REQUEST_CLASSES,
    Ping,
    Role,
)
from pymotoros.protocol.messages._base import NoFields
from pymotoros.protocol.sizes import (
    ECHO_ON_SHORT,
    IO_SIZES,
    MOTION_CLOSE_TYPES,
    MOTION_SIZES,
)

# What MotoROS 1.9.12 handles, per direction and port: msg_type -> class name.
# Requests: what each server reads (§1.5; the motion port also sizes 13/15/2002/2017
# and then closes). Replies: what the controller sends (§1.4, §1.6, §2).
EXPECTED_REQUESTS: dict[Port, dict[int, str]] = {
    Port.MOTION: {
        1: "Ping",
        13: "RobotStatus",
        14: "JointTrajPtFull",
        15: "JointFeedback",
        2001: "MotoMotionCtrl",
        2002: "MotoMotionReply",
        2003: "MotoReadIoBit",
        2005: "MotoWriteIoBit",
        2007: "MotoReadIoGroup",
        2009: "MotoWriteIoGroup",
        2016: "MotoJointTrajPtFullEx",
        2017: "MotoJointFeedbackEx",
        2018: "MotoSelectTool",
        2020: "MotoGetDhParameters",
    },
    Port.IO: {
        2003: "MotoReadIoBit",
        2005: "MotoWriteIoBit",
        2007: "MotoReadIoGroup",
        2009: "MotoWriteIoGroup",
        2012: "MotoReadMRegister",
        2013: "MotoWriteMRegister",
    },
    Port.STATE: {},  # the state server never reads its sockets (§2.3)
}
EXPECTED_REPLIES: dict[Port, dict[int, str]] = {
    Port.MOTION: {
        1: "PingReply",
        2002: "MotoMotionReply",
        2004: "MotoReadIoBitReply",
        2006: "MotoWriteIoBitReply",
        2008: "MotoReadIoGroupReply",
        2010: "MotoWriteIoGroupReply",
        2020: "MotoGetDhParametersReply",
    },
    Port.IO: {
        2002: "IoErrorReply",
        2004: "MotoReadIoBitReply",
        2006: "MotoWriteIoBitReply",
        2008: "MotoReadIoGroupReply",
        2010: "MotoWriteIoGroupReply",
        2012: "MotoReadMRegisterReply",
        2013: "MotoWriteMRegisterReply",
    },
    Port.STATE: {13: "RobotStatus", 15: "JointFeedback", 2017: "MotoJointFeedbackEx"},
}
NEVER_HANDLED = {MsgType.GET_VERSION, MsgType.MOTO_IOCTRL_REPLY}
"""Defined in SimpleMessage.h, handled nowhere: answered 3003 on every port (§1.3)."""

# Body sizes of §1.4, by class name (FULL_EX: the 8-byte head, 132 more per group).
EXPECTED_BODY_SIZE = {
    "Ping": 0,
    "PingReply": 0,
    "RobotStatus": 28,
    "JointTrajPtFull": 136,
    "JointFeedback": 132,
    "JointTrajPtExData": 132,
    "MotoMotionCtrl": 52,
    "MotoMotionReply": 60,
    "MotoReadIoBit": 4,
    "MotoReadIoBitReply": 8,
    "MotoWriteIoBit": 8,
    "MotoWriteIoBitReply": 4,
    "MotoReadIoGroup": 4,
    "MotoReadIoGroupReply": 8,
    "MotoWriteIoGroup": 8,
    "MotoWriteIoGroupReply": 4,
    "MotoReadMRegister": 4,
    "MotoReadMRegisterReply": 8,
    "MotoWriteMRegister": 8,
    "MotoWriteMRegisterReply": 4,
    "IoErrorReply": 60,
    "MotoJointTrajPtFullEx": 8,
    "MotoJointFeedbackEx": 532,
    "MotoSelectTool": 12,
    "MotoGetDhParameters": 0,
    "MotoGetDhParametersReply": 512,
}

ENTRIES = [
    (direction, port, msg_type, cls)
    for direction, tables in (("request", REQUEST_CLASSES), ("reply", REPLY_CLASSES))
    for port, table in tables.items()
    for msg_type, cls in table.items()
]
STRATEGY_OF = {COVERED[name]: MESSAGES[name][0] for name in MESSAGES}
ORDERS = [ByteOrder.LITTLE, ByteOrder.BIG]


Tables = Mapping[Port, Mapping[int, type[Message]]]


def _names(tables: Tables) -> dict[Port, dict[int, str]]:
    return {
        port: {msg_type: cls.__name__ for msg_type, cls in table.items()}
        for port, table in tables.items()
    }


def test_requests_are_exactly_what_motoros_reads() -> None:
    assert _names(REQUEST_CLASSES) == EXPECTED_REQUESTS


def test_replies_are_exactly_what_motoros_sends() -> None:
    assert _names(REPLY_CLASSES) == EXPECTED_REPLIES


def test_every_handled_msg_type_has_a_class_and_the_others_none() -> None:
    registered = {t for tables in (REQUEST_CLASSES, REPLY_CLASSES) for t in _all_types(tables)}
    assert registered == {int(t) for t in MsgType} - {int(t) for t in NEVER_HANDLED}


def _all_types(tables: Tables) -> set[int]:
    return {msg_type for table in tables.values() for msg_type in table}


def test_every_message_class_is_exported_and_sized() -> None:
    """Every class of the package is public and has its §1.4 size (nothing hand-listed)."""
    classes = {
        name: obj
        for name in messages_package.__all__
        if isinstance(obj := getattr(messages_package, name), type)
        and issubclass(obj, Message)
        and obj is not Message
    }
    assert {name: cls.BODY_SIZE for name, cls in classes.items()} == EXPECTED_BODY_SIZE
    registered = {cls for _d, _p, _t, cls in ENTRIES}
    assert set(classes.values()) - registered == {classes["JointTrajPtExData"]}


def test_a_class_travels_the_way_its_role_says() -> None:
    """Requests are read by servers only; replies and topics come from the controller,
    or are sized by the motion server before it closes (§1.5)."""
    for direction, port, msg_type, cls in ENTRIES:
        assert int(cls.MSG_TYPE) == msg_type
        if direction == "reply":
            assert cls.ROLE is not Role.REQUEST, cls
        elif cls.ROLE is not Role.REQUEST:
            assert port is Port.MOTION, cls
            assert msg_type in MOTION_CLOSE_TYPES, cls


def test_named_body_sizes_are_the_reference_numbers() -> None:
    assert BODY_SIZE_GROUP_RECORD == 132
    assert BODY_SIZE_TRAJ_PT_FULL == 136
    assert BODY_SIZE_FULL_EX_HEAD == 8
    assert BODY_SIZE_FEEDBACK_EX == 532
    assert BODY_SIZE_MOTION_REPLY == 60
    assert BODY_SIZE_DH_REPLY == 512


def test_size_tables_are_derived_from_the_classes() -> None:
    for port, sizes in ((Port.MOTION, MOTION_SIZES), (Port.IO, IO_SIZES)):
        for msg_type, total in sizes.items():
            assert total == FRAME_OVERHEAD + REQUEST_CLASSES[port][msg_type].BODY_SIZE
    assert sorted(MOTION_CLOSE_TYPES) == [13, 15, 2002, 2017]
    assert sorted(ECHO_ON_SHORT) == [14, 2001, 2016, 2018]


@pytest.mark.parametrize(
    ("direction", "port", "msg_type", "cls"),
    ENTRIES,
    ids=[f"{d}-{p.value}-{t}-{c.__name__}" for d, p, t, c in ENTRIES],
)
@given(data=st.data())
@settings(max_examples=10)
def test_every_registered_class_round_trips_on_its_port(
    direction: str, port: Port, msg_type: int, cls: type[Message], data: st.DataObject
) -> None:
    """encode, then the decoder of that port and direction, gives back the same message."""
    message = data.draw(STRATEGY_OF[cls])
    for order in ORDERS:
        decoder = FrameDecoder(order)
        decoder.feed(encode(message, order))
        if direction == "request":
            assert decoder.next_request(port) == message
        else:
            assert decoder.next_reply(port) == message
        assert decoder.buffered == 0


def test_a_second_class_for_a_registered_type_and_port_is_refused() -> None:
    with pytest.raises(TypeError, match="already Ping"):

        class _SecondPing(Message, NoFields):
            __slots__ = ()
            MSG_TYPE: ClassVar[MsgType] = MsgType.PING
            ROLE: ClassVar[Role] = Role.REQUEST
            REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.IO, Port.MOTION)

    # all or nothing: the IO port did not get the refused class either
    assert int(MsgType.PING) not in REQUEST_CLASSES[Port.IO]
    assert REQUEST_CLASSES[Port.MOTION][int(MsgType.PING)] is Ping


def test_subclassing_a_message_registers_nothing() -> None:
    """Only what a class declares itself is registered: a subclass inherits no entry."""
    before = {port: dict(table) for port, table in REQUEST_CLASSES.items()}

    class _TracedPing(Ping):
        __slots__ = ()

    assert {port: dict(table) for port, table in REQUEST_CLASSES.items()} == before
    assert _TracedPing().pack(ByteOrder.LITTLE) == b""


@pytest.mark.parametrize("name", sorted(MESSAGES))
@given(data=st.data())
@settings(max_examples=10)
def test_reply_echo_agrees_with_the_clients_hand_written_table(
    name: str, data: st.DataObject
) -> None:
    """``Message.reply_echo`` (derived from the layout) says what the client's
    ``expected_echo`` (one branch per request class) says, so the client can use it."""
    message = data.draw(MESSAGES[name][0])
    assert message.reply_echo() == expected_echo(message)
