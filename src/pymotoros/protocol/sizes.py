"""MotoROS's size-by-type rules (reference §1.5) as data, and the verdict they give.

MotoROS never reads the length prefix: it decides from ``msg_type`` alone how
many bytes a message must have, and answers a short message with 3001, an
unknown type with 3003, and a state message sent to the motion port by closing
the connection. A client must not be able to tell our servers from the real
one, so the servers ask :func:`check_request` what to do with every frame.

Our servers reassemble fragments with :class:`~pymotoros.protocol.framing.FrameDecoder`
(the real controller answers 3001 to a fragment; see docs/protocol.md), so a
"short" message here is a complete frame whose body is shorter than its type
needs: a peer that sent a wrong prefix.

All sizes in this module are *total* sizes on the wire (prefix + header + body),
because that is what MotoROS compares against what ``recv`` returned.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final, TypeAlias

from pymotoros.protocol.constants import (
    MAX_MESSAGE_SIZE,
    ByteOrder,
    CommType,
    InvalidSubcode,
    MsgType,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import FRAME_OVERHEAD, Frame, decode_request
from pymotoros.protocol.messages import (
    FULL_EX_SIZE_UNKNOWN_BELOW,
    REQUEST_CLASSES,
    IoErrorReply,
    Message,
    MotoMotionReply,
    Role,
    UnknownMessage,
)

__all__ = [
    "ECHO_ON_SHORT",
    "FULL_EX_SIZE_UNKNOWN_BELOW",
    "IO_SIZES",
    "MOTION_CLOSE_TYPES",
    "MOTION_SIZES",
    "Accept",
    "Close",
    "Reject",
    "Verdict",
    "check_request",
    "expected_size",
    "is_length_mismatch",
    "short_message_reply",
    "unknown_type_reply",
]

# --------------------------------------------------------------------------- the table (§1.5)
# Derived from the message classes: what a server decodes on a port (REQUEST_ON) is
# what MotoROS sizes there, and a class's BODY_SIZE is the size MotoROS expects.


def _sizes(port: Port) -> Mapping[int, int]:
    """Total size per fixed-size type a server reads on ``port`` (FULL_EX aside)."""
    return MappingProxyType(
        {
            msg_type: FRAME_OVERHEAD + cls.BODY_SIZE
            for msg_type, cls in REQUEST_CLASSES[port].items()
            if cls.FIXED_SIZE
        }
    )


def _echoes_sequence(cls: type[Message]) -> bool:
    """A client's request MotoROS answers with an echo of its sequence (§1.5, §1.6)."""
    return cls.ROLE is Role.REQUEST and "sequence" in cls.OFFSETS


MOTION_SIZES: Final[Mapping[int, int]] = _sizes(Port.MOTION)
"""Motion port (§1.5): total size per known type, FULL_EX (2016) aside (computed from n).
2, 2004..2011 and the M-register types 2012/2013 are *unknown* here."""

IO_SIZES: Final[Mapping[int, int]] = _sizes(Port.IO)
"""IO port (§1.5): only the six IO request types are known."""

MOTION_CLOSE_TYPES: Final = frozenset(
    msg_type
    for msg_type, cls in REQUEST_CLASSES[Port.MOTION].items()
    if cls.ROLE is not Role.REQUEST
)
"""Known sizes the motion server does not process: MotoROS drops the connection (§1.5).

These are the classes the motion port decodes that are not requests (13/15/2002/2017)."""

_SEQUENCE_OFFSET: Final[Mapping[int, int]] = MappingProxyType(
    {
        msg_type: cls.OFFSETS["sequence"]
        for msg_type, cls in REQUEST_CLASSES[Port.MOTION].items()
        if _echoes_sequence(cls)
    }
)
"""Body offset of the sequence echoed in a 3001 reply (SELECT_TOOL's comes third, §1.4)."""

ECHO_ON_SHORT: Final = frozenset(_SEQUENCE_OFFSET)
"""Types whose 3001 reply has groupNo 0 and echoes sequence (and command) (§1.5, §1.6):
the motion-port requests that carry a sequence."""

_COMMAND_OFFSET: Final[Mapping[int, int]] = MappingProxyType(
    {
        msg_type: cls.OFFSETS["command"]
        for msg_type, cls in REQUEST_CLASSES[Port.MOTION].items()
        if _echoes_sequence(cls) and "command" in cls.OFFSETS
    }
)
"""Body offset of the command a 3001 reply echoes (MOTO_MOTION_CTRL's, §1.4); the others
echo their type."""

_NO_GROUP: Final = -1
"""groupNo and sequence of a reply that belongs to no request (§1.6)."""


_MOTION: Final = Port.MOTION
_IO: Final = Port.IO
_MOTION_REQUESTS: Final = REQUEST_CLASSES[Port.MOTION]
_IO_REQUESTS: Final = REQUEST_CLASSES[Port.IO]
_SERVICE_REPLY: Final = int(CommType.SERVICE_REPLY)


def _int_at(body: bytes, offset: int, order: ByteOrder) -> int:
    """int32 at ``offset``, with missing bytes read as zero (MotoROS's zero-filled buffer)."""
    chunk = body[offset : offset + 4].ljust(4, b"\0")
    value: int = struct.unpack(order + "i", chunk)[0]
    return value


def expected_size(msg_type: int, port: Port, body: bytes, order: ByteOrder) -> int | None:
    """Total bytes MotoROS wants for this type on this port, or None if the type is unknown.

    FULL_EX: 24 + 132·n with n read from the body; 552 when n is not there yet
    (see ``MotoJointTrajPtFullEx.needed_body_size``).
    """
    # Identity tests on the port, not a lookup keyed by it: Enum hashing is a Python call,
    # and the motion server sizes every request (several per streamed point).
    if port is _MOTION:
        table = _MOTION_REQUESTS
    elif port is _IO:
        table = _IO_REQUESTS
    else:
        raise ValueError(f"MotoROS reads no requests on the {port.value} port")
    cls = table.get(msg_type)
    if cls is None:
        return None
    return FRAME_OVERHEAD + cls.needed_body_size(body, order)


# --------------------------------------------------------------------------- error replies


def unknown_type_reply(msg_type: int, port: Port) -> MotoMotionReply | IoErrorReply:
    """INVALID/3003 as MotoROS sends it: group -1, sequence -1, command = the type."""
    if port is Port.IO:
        return IoErrorReply(ResultCode.INVALID, InvalidSubcode.MSGTYPE)
    return MotoMotionReply(
        _NO_GROUP, _NO_GROUP, msg_type, ResultCode.INVALID, InvalidSubcode.MSGTYPE
    )


def short_message_reply(
    frame: Frame, order: ByteOrder, port: Port
) -> MotoMotionReply | IoErrorReply:
    """INVALID/3001 for a body shorter than its type needs (§1.5).

    For MOTION_CTRL, TRAJ_PT_FULL, FULL_EX and SELECT_TOOL the reply has groupNo 0
    and echoes the sequence (and MOTION_CTRL's command; the others' command is
    their type); bytes that did not arrive read as zero. Any other type gets
    group -1, sequence -1, command = type. On the IO port it is the IO error reply.
    """
    if port is Port.IO:
        return IoErrorReply(ResultCode.INVALID, InvalidSubcode.MSGSIZE)
    msg_type = frame.msg_type
    offset = _SEQUENCE_OFFSET.get(msg_type)
    if offset is None:
        return MotoMotionReply(
            _NO_GROUP, _NO_GROUP, msg_type, ResultCode.INVALID, InvalidSubcode.MSGSIZE
        )
    sequence = _int_at(frame.body, offset, order)
    command_offset = _COMMAND_OFFSET.get(msg_type)
    command = msg_type if command_offset is None else _int_at(frame.body, command_offset, order)
    return MotoMotionReply(0, sequence, command, ResultCode.INVALID, InvalidSubcode.MSGSIZE)


# --------------------------------------------------------------------------- the verdict


@dataclass(frozen=True, slots=True)
class Accept:
    """Process ``message``.

    ``surplus`` counts body bytes beyond what the type needs; MotoROS ignores
    them here (worth a log line). ``reply_expected`` is False for a SERVICE_REPLY
    comm type on the motion port: MotoROS processes it but sends nothing (§1.1).
    """

    message: Message
    surplus: int = 0
    reply_expected: bool = True


@dataclass(frozen=True, slots=True)
class Reject:
    """Send ``reply`` (INVALID/3001 or 3003) and keep the connection."""

    reply: MotoMotionReply | IoErrorReply
    subcode: InvalidSubcode


@dataclass(frozen=True, slots=True)
class Close:
    """Close the connection without a reply (motion port, types 13/15/2002/2017)."""

    msg_type: int
    reason: str


Verdict: TypeAlias = Accept | Reject | Close
"""What a server does with a request, decided from its header and size before the body is read."""


def check_request(frame: Frame, order: ByteOrder, port: Port) -> Verdict:
    """What MotoROS does with this complete frame on the motion or IO port (§1.5)."""
    msg_type = frame.msg_type
    expected = expected_size(msg_type, port, frame.body, order)
    if expected is None:
        return Reject(unknown_type_reply(msg_type, port), InvalidSubcode.MSGTYPE)
    received = FRAME_OVERHEAD + len(frame.body)
    if received < expected:
        return Reject(short_message_reply(frame, order, port), InvalidSubcode.MSGSIZE)
    if port is _MOTION and msg_type in MOTION_CLOSE_TYPES:
        return Close(msg_type, f"{MsgType.describe(msg_type)} is not a request (§1.5)")
    if received != expected:  # surplus bytes: MotoROS reads what the type needs
        body = frame.body[: expected - FRAME_OVERHEAD]
        frame = Frame(msg_type, frame.comm_type, frame.reply_type, body)
    message = decode_request(frame, order, port)
    if isinstance(message, UnknownMessage):  # pragma: no cover - the tables agree (tested)
        raise RuntimeError(f"bug: type {msg_type} has a size on {port} but no class")
    reply_expected = not (port is _MOTION and frame.comm_type == _SERVICE_REPLY)
    return Accept(message, received - expected, reply_expected)


def is_length_mismatch(frame: Frame, verdict: Verdict) -> bool:
    """Whether a whole frame's length prefix disagrees with its type's size (the client
    lint's length-mismatch; the one place this is decided for frames cut by the prefix):
    a short one (3001 MSGSIZE) or one with spare bytes, except a FULL_EX padded to 552
    bytes, which MotoROS takes whole as its message struct (§1.5)."""
    if isinstance(verdict, Reject):
        return verdict.subcode == InvalidSubcode.MSGSIZE
    padded_ex = (
        frame.msg_type == MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX and frame.size == MAX_MESSAGE_SIZE
    )
    return isinstance(verdict, Accept) and verdict.surplus > 0 and not padded_ex
