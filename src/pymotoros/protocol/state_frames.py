"""The state server's frames in one ``struct.pack`` each: JOINT_FEEDBACK and ROBOT_STATUS.

Why: a twin sends a state cycle every 25 ms of virtual time, so in a user's CI run the
cycle's encoding is paid forty times per simulated second. Building a validated
:class:`~pymotoros.protocol.messages.JointFeedback` and then
:func:`~pymotoros.protocol.framing.encode` costs two validations and two packs per
message; here the prefix, header and body are one precompiled ``Struct`` over the same
layout (the message classes' own body formats, so the layout is declared once).

The bytes are exactly those of ``encode(JointFeedback(...), order)`` and
``encode(RobotStatus(...), order)`` (``tests/protocol/test_state_frames.py`` compares
them on random values, both byte orders). The values come from the controller, which
only produces finite float32 values and small ints, so no validation is repeated here.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Final

from pymotoros.protocol.constants import (
    HEADER_SIZE,
    ByteOrder,
    CommType,
    MsgType,
    ReplyType,
)
from pymotoros.protocol.messages import JointFeedback, RobotStatus

__all__ = ["joint_feedback_frame", "robot_status_frame"]

_ZERO_ACC: Final = (0.0,) * 10
"""JOINT_FEEDBACK's acc: MotoROS sends zeros (§2.4)."""


def _frame_structs(body: struct.Struct) -> dict[str, struct.Struct]:
    """Prefix (length), header (type, comm, reply) and ``body``, per byte order."""
    fmt = body.format.lstrip("<>!=@")
    return {
        order: struct.Struct(f"{order}iiii{fmt}") for order in (ByteOrder.LITTLE, ByteOrder.BIG)
    }


_FEEDBACK: Final = _frame_structs(JointFeedback._STRUCTS[0])
_STATUS: Final = _frame_structs(RobotStatus._STRUCTS[0])
_FEEDBACK_HEAD: Final = (
    HEADER_SIZE + JointFeedback.BODY_SIZE,
    int(MsgType.JOINT_FEEDBACK),
    int(CommType.TOPIC),  # a topic's header, as encode() fills it (§1.2)
    int(ReplyType.INVALID),
)
_STATUS_HEAD: Final = (
    HEADER_SIZE + RobotStatus.BODY_SIZE,
    int(MsgType.ROBOT_STATUS),
    int(CommType.TOPIC),
    int(ReplyType.INVALID),
)


def joint_feedback_frame(
    order: ByteOrder,
    group_no: int,
    valid_fields: int,
    pos: Sequence[float],
    vel: Sequence[float],
) -> bytes:
    """``encode(JointFeedback(group_no, valid_fields, 0.0, pos, vel), order)``; 10 values each."""
    return _FEEDBACK[order].pack(
        *_FEEDBACK_HEAD,
        group_no,
        valid_fields,
        0.0,
        *pos,
        *vel,
        *_ZERO_ACC,
    )


def robot_status_frame(order: ByteOrder, fields: Sequence[int]) -> bytes:
    """``encode(RobotStatus(*fields), order)``: the seven status fields in wire order."""
    return _STATUS[order].pack(*_STATUS_HEAD, *fields)
