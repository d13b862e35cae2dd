"""The motion port's own messages: PING, MOTION_CTRL, its MOTION_REPLY and SELECT_TOOL (§1.4).

Trajectory points (also motion-port requests) are in :mod:`.trajectory`, the IO
requests the motion port also answers in :mod:`.io`, GET_DH_PARAMETERS in :mod:`.dh`.
"""

from __future__ import annotations

from typing import ClassVar, Final, NamedTuple

from pymotoros.protocol.constants import MsgType, Port
from pymotoros.protocol.messages._base import (
    I32,
    JOINTS,
    ZERO_JOINTS,
    Kind,
    Message,
    NoFields,
    Role,
)

__all__ = [
    "BODY_SIZE_MOTION_REPLY",
    "MotoMotionCtrl",
    "MotoMotionReply",
    "MotoSelectTool",
    "Ping",
    "PingReply",
]


class Ping(Message, NoFields):
    """PING request (type 1, empty body); MotoROS answers with an empty PING reply."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.PING
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)


class PingReply(Message, NoFields):
    """The PING reply: same type 1, comm SERVICE_REPLY, reply SUCCESS, empty body."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.PING
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)


class _Ctrl(NamedTuple):
    group_no: int
    sequence: int
    command: int
    data: tuple[float, ...] = ZERO_JOINTS


class MotoMotionCtrl(Message, _Ctrl):
    """MOTO_MOTION_CTRL (2001): a motion command (:class:`MotionCommand`) for a group.

    ``data`` is ignored by MotoROS; ``command`` stays an int so that an unknown
    code can be decoded and answered.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_MOTION_CTRL
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (
        ("group_no", I32),
        ("sequence", I32),
        ("command", I32),
        ("data", JOINTS),
    )


class _Reply(NamedTuple):
    group_no: int
    sequence: int
    command: int
    result: int
    subcode: int
    data: tuple[float, ...] = ZERO_JOINTS


class MotoMotionReply(Message, _Reply):
    """MOTO_MOTION_REPLY (2002): the answer to every motion-port request.

    ``command`` echoes the request's command (MOTION_CTRL) or its msg_type; the
    outcome is ``result`` + ``subcode`` (the header always says SUCCESS, §1.2).
    For CHECK_QUEUE_CNT the count travels in ``subcode``. The motion server also
    decodes one from a client, to size it and close the connection (§1.5).
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_MOTION_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (
        ("group_no", I32),
        ("sequence", I32),
        ("command", I32),
        ("result", I32),
        ("subcode", I32),
        ("data", JOINTS),
    )


BODY_SIZE_MOTION_REPLY: Final = MotoMotionReply.BODY_SIZE
"""60: groupNo, sequence, command, result, subcode, data[10] (§1.4)."""


class _Tool(NamedTuple):
    group_no: int
    tool: int
    sequence: int


class MotoSelectTool(Message, _Tool):
    """MOTO_SELECT_TOOL (2018). Field order on the wire is groupNo, tool, sequence."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_SELECT_TOOL
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (
        ("group_no", I32),
        ("tool", I32),
        ("sequence", I32),
    )
