"""Frames on a byte stream: length prefix, 12-byte header, body (reference §1.1–1.2).

TCP delivers bytes, not messages: a ``recv`` may hold half a frame or three of
them. :class:`FrameDecoder` reassembles whatever it is fed and yields whole
:class:`Frame` objects. It trusts the length prefix only within the sizes that
MotoROS can produce (12..548), so a hostile or desynchronised peer costs a
typed error, never an unbounded buffer. (MotoROS itself ignores the prefix and
answers a fragment with 3001; reassembling is our documented improvement.)

Turning a frame into a typed message needs to know *who* sent it and on which
port: type 2012 is a request from a client but a reply from the controller,
and type 2002 is a MOTION_REPLY on the motion port but the IO error reply on
the IO port. Hence :func:`decode_request` (server side) and
:func:`decode_reply` (client side).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterator, Mapping
from types import MappingProxyType
from typing import Final, NamedTuple, TypeAlias

from pymotoros.errors import LocalProtocolError, RemoteProtocolError
from pymotoros.protocol.constants import (
    HEADER_SIZE,
    MAX_LENGTH_PREFIX,
    MAX_WIRE_MESSAGE_SIZE,
    PREFIX_SIZE,
    ByteOrder,
    CommType,
    Port,
    ReplyType,
)
from pymotoros.protocol.messages import (
    IoErrorReply,
    JointFeedback,
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
    RobotStatus,
    Role,
    UnknownMessage,
    WireMessage,
)

__all__ = [
    "FRAME_OVERHEAD",
    "MIN_LENGTH_PREFIX",
    "REPLY_CLASSES",
    "REQUEST_CLASSES",
    "Frame",
    "FrameDecoder",
    "decode_reply",
    "decode_request",
    "encode",
    "encode_frame",
    "header_problem",
]

MIN_LENGTH_PREFIX: Final = HEADER_SIZE
"""Smallest legal prefix value: a header with an empty body (PING, GET_DH request)."""

FRAME_OVERHEAD: Final = PREFIX_SIZE + HEADER_SIZE
"""16 bytes in front of every body."""

_COMPACT_AFTER: Final = 1 << 16
"""Consumed bytes the decoder tolerates at the front of its buffer before trimming."""

_HEAD_LE: Final = struct.Struct("<iiii")
_HEAD_BE: Final = struct.Struct(">iiii")
_PREFIX_LE: Final = struct.Struct("<i")
_PREFIX_BE: Final = struct.Struct(">i")


class Frame(NamedTuple):
    """One whole message as it came off the wire: header fields plus the raw body.

    ``msg_type``, ``comm_type`` and ``reply_type`` are plain ints: MotoROS does
    not check the incoming header, so neither does the decoder.
    """

    msg_type: int
    comm_type: int
    reply_type: int
    body: bytes

    @property
    def size(self) -> int:
        """Bytes on the wire including prefix and header."""
        return FRAME_OVERHEAD + len(self.body)


# --------------------------------------------------------------------------- encoding

_DEFAULT_HEADER: Final[Mapping[Role, tuple[int, int]]] = MappingProxyType(
    {
        Role.REQUEST: (CommType.SERVICE_REQUEST, ReplyType.INVALID),
        Role.REPLY: (CommType.SERVICE_REPLY, ReplyType.SUCCESS),
        Role.TOPIC: (CommType.TOPIC, ReplyType.INVALID),
    }
)


def encode_frame(frame: Frame, order: ByteOrder) -> bytes:
    """Serialize a raw frame; the prefix is computed from the body (used for raw/test frames)."""
    head = _HEAD_BE if order == ">" else _HEAD_LE
    length = HEADER_SIZE + len(frame.body)
    try:
        prefix = head.pack(length, frame.msg_type, frame.comm_type, frame.reply_type)
    except struct.error as exc:
        raise LocalProtocolError(f"cannot encode header of {frame!r}: {exc}") from None
    return prefix + frame.body


def encode(
    message: WireMessage,
    order: ByteOrder,
    *,
    comm_type: int | None = None,
    reply_type: int | None = None,
) -> bytes:
    """The whole frame for ``message``: prefix, header and body, ready for one ``send``.

    The header defaults follow the message's role exactly as MotoROS and the ROS
    driver fill it (§1.2): requests SERVICE_REQUEST/INVALID, replies
    SERVICE_REPLY/SUCCESS, topics TOPIC/INVALID. IO replies (2004/2006/2008/
    2010 and the M-register replies) default to FAILURE when ``result_code`` is
    non-zero, as MotoROS sends them; pass ``reply_type`` to override anything.
    """
    body = message.pack(order)
    default_comm, default_reply = _DEFAULT_HEADER[message.ROLE]
    if reply_type is None:
        reply_type = default_reply
        if message.IO_RESULT and getattr(message, "result_code", 0) != 0:
            reply_type = ReplyType.FAILURE
    if comm_type is None:
        comm_type = default_comm
    msg_type = message.msg_type if isinstance(message, UnknownMessage) else message.MSG_TYPE
    head = _HEAD_BE if order == ">" else _HEAD_LE
    length = HEADER_SIZE + len(body)
    if length > MAX_LENGTH_PREFIX:
        raise LocalProtocolError(
            f"{type(message).__name__}: {length + PREFIX_SIZE} bytes exceed the "
            f"{MAX_WIRE_MESSAGE_SIZE}-byte maximum of MotoROS"
        )
    try:
        prefix = head.pack(length, msg_type, comm_type, reply_type)
    except struct.error as exc:
        raise LocalProtocolError(f"header of {type(message).__name__}: {exc}") from None
    return prefix + body


def header_problem(frame: Frame) -> str | None:
    """Why the ROS driver's ``simple_message`` would refuse this header, or None (clients §2.2).

    MotoROS never checks headers; real clients do, so a faithful server must
    never send a frame for which this returns a reason.
    """
    if frame.msg_type == 0:
        return "msg_type 0"
    if frame.comm_type == CommType.INVALID:
        return "comm_type INVALID (0)"
    if frame.comm_type == CommType.SERVICE_REPLY:
        if frame.reply_type == ReplyType.INVALID:
            return "a SERVICE_REPLY with reply_type INVALID (0)"
    elif frame.reply_type != ReplyType.INVALID:
        return f"reply_type {frame.reply_type} on a message that is not a SERVICE_REPLY"
    return None


# --------------------------------------------------------------------------- stream decoding


class FrameDecoder:
    """Bytes in, :class:`Frame` objects out. No sockets, no clock.

    ``feed`` any chunks; call ``next_frame`` until it returns None. A length
    prefix outside 12..548 raises :class:`RemoteProtocolError` carrying the
    offending bytes; the decoder keeps raising until :meth:`discard` drops its
    buffer (there is no reliable way to find the next frame boundary in a
    Simple Message stream, so resynchronising is the caller's decision).
    """

    __slots__ = ("_buf", "_head", "_order", "_pos", "_prefix")

    def __init__(self, order: ByteOrder) -> None:
        self._order = order
        self._head = _HEAD_BE if order == ">" else _HEAD_LE
        self._prefix = _PREFIX_BE if order == ">" else _PREFIX_LE
        self._buf = b""
        self._pos = 0

    @property
    def order(self) -> ByteOrder:
        return self._order

    @property
    def buffered(self) -> int:
        """Bytes received but not yet returned as frames (a partial frame at most, normally)."""
        return len(self._buf) - self._pos

    def feed(self, data: bytes | bytearray | memoryview) -> None:
        """Append received bytes; nothing is parsed until :meth:`next_frame`."""
        if self._pos == len(self._buf):
            # nothing pending (the normal case): keep the chunk itself, no copy for bytes
            self._buf = data if type(data) is bytes else bytes(data)
            self._pos = 0
            return
        if self._pos:
            self._buf = self._buf[self._pos :]
            self._pos = 0
        self._buf += data

    def next_frame(self) -> Frame | None:
        """The next whole frame, or None if more bytes are needed."""
        buf = self._buf
        pos = self._pos
        size = len(buf)
        if size - pos >= FRAME_OVERHEAD:
            # hot path: prefix and header in one unpack
            length, msg_type, comm_type, reply_type = self._head.unpack_from(buf, pos)
        elif size - pos >= PREFIX_SIZE:
            (length,) = self._prefix.unpack_from(buf, pos)
        else:
            return None
        if length < MIN_LENGTH_PREFIX or length > MAX_LENGTH_PREFIX:
            raise RemoteProtocolError(
                f"length prefix {length} outside {MIN_LENGTH_PREFIX}..{MAX_LENGTH_PREFIX}",
                data=buf[pos : pos + MAX_WIRE_MESSAGE_SIZE],
            )
        end = pos + PREFIX_SIZE + length
        if end > size:
            return None
        body = buf[pos + FRAME_OVERHEAD : end]
        if end == size:
            self._buf = b""
            self._pos = 0
        elif end > _COMPACT_AFTER:
            self._buf = buf[end:]
            self._pos = 0
        else:
            self._pos = end
        return _new_frame(Frame, (msg_type, comm_type, reply_type, body))

    def next_reply(self, port: Port) -> WireMessage | None:
        """:meth:`next_frame` then :func:`decode_reply` in one step: the client's hot path.

        Faster because no :class:`Frame` or body copy is made; the header's comm
        and reply types are not returned (use the two-step form to inspect them).
        A frame whose body does not fit its type is consumed, then reported as
        :class:`RemoteProtocolError`.
        """
        # The framing of _next_message, inlined: this path decodes every state
        # message a client receives, and the extra call costs ~5 % of it.
        table = (
            _REP_STATE_FROM
            if port is _STATE
            else _REP_MOTION_FROM
            if port is _MOTION
            else _REP_IO_FROM
        )
        buf = self._buf
        pos = self._pos
        size = len(buf)
        if size - pos < FRAME_OVERHEAD:
            return self._next_message(table)  # partial: the general path decides
        length, msg_type, _, _ = self._head.unpack_from(buf, pos)
        end = pos + PREFIX_SIZE + length
        if length < MIN_LENGTH_PREFIX or length > MAX_LENGTH_PREFIX or end > size:
            return self._next_message(table)  # bad prefix or incomplete
        if end == size:
            self._buf = b""
            self._pos = 0
        elif end > _COMPACT_AFTER:
            self._buf = buf[end:]
            self._pos = 0
        else:
            self._pos = end
        unpack_from = table.get(msg_type)
        if unpack_from is None:
            return UnknownMessage(msg_type, buf[pos + FRAME_OVERHEAD : end])
        return unpack_from(buf, pos + FRAME_OVERHEAD, end, self._order)

    def next_request(self, port: Port) -> WireMessage | None:
        """:meth:`next_frame` then :func:`decode_request` in one step (exact sizes only).

        Servers that follow MotoROS's size rules use :meth:`next_frame` and
        :func:`sizes.check_request` instead.
        """
        table = (
            _REQ_MOTION_FROM
            if port is _MOTION
            else _REQ_STATE_FROM
            if port is _STATE
            else _REQ_IO_FROM
        )
        return self._next_message(table)

    def _next_message(self, table: Mapping[int, _UnpackFrom]) -> WireMessage | None:
        # Same framing as next_frame, kept inline: a helper call costs ~10 % here.
        buf = self._buf
        pos = self._pos
        size = len(buf)
        if size - pos >= FRAME_OVERHEAD:
            length, msg_type, _, _ = self._head.unpack_from(buf, pos)
        elif size - pos >= PREFIX_SIZE:
            (length,) = self._prefix.unpack_from(buf, pos)
        else:
            return None
        if length < MIN_LENGTH_PREFIX or length > MAX_LENGTH_PREFIX:
            raise RemoteProtocolError(
                f"length prefix {length} outside {MIN_LENGTH_PREFIX}..{MAX_LENGTH_PREFIX}",
                data=buf[pos : pos + MAX_WIRE_MESSAGE_SIZE],
            )
        end = pos + PREFIX_SIZE + length
        if end > size:
            return None
        if end == size:
            self._buf = b""
            self._pos = 0
        elif end > _COMPACT_AFTER:
            self._buf = buf[end:]
            self._pos = 0
        else:
            self._pos = end
        start = pos + FRAME_OVERHEAD
        unpack_from = table.get(msg_type)
        if unpack_from is None:
            return UnknownMessage(msg_type, buf[start:end])
        return unpack_from(buf, start, end, self._order)

    def frames(self) -> Iterator[Frame]:
        """Every whole frame currently buffered (stops at the first incomplete one)."""
        while (frame := self.next_frame()) is not None:
            yield frame

    def discard(self) -> bytes:
        """Drop and return everything buffered: the way to resynchronise after an error."""
        dropped = self._buf[self._pos :]
        self._buf = b""
        self._pos = 0
        return dropped


_new_frame: Final = tuple.__new__


# --------------------------------------------------------------------------- typed decoding


def _table(*classes: type[Message]) -> Mapping[int, type[Message]]:
    return MappingProxyType({int(cls.MSG_TYPE): cls for cls in classes})


_IO_BIT_GROUP_REQUESTS: Final = (MotoReadIoBit, MotoWriteIoBit, MotoReadIoGroup, MotoWriteIoGroup)
_IO_BIT_GROUP_REPLIES: Final = (
    MotoReadIoBitReply,
    MotoWriteIoBitReply,
    MotoReadIoGroupReply,
    MotoWriteIoGroupReply,
)

REQUEST_CLASSES: Final[Mapping[Port, Mapping[int, type[Message]]]] = MappingProxyType(
    {
        # The motion port also decodes 13/15/2002/2017: MotoROS sizes them and then
        # closes the connection (sizes.py decides that; here we only decode).
        Port.MOTION: _table(
            Ping,
            JointTrajPtFull,
            MotoMotionCtrl,
            MotoJointTrajPtFullEx,
            MotoSelectTool,
            MotoGetDhParameters,
            *_IO_BIT_GROUP_REQUESTS,
            RobotStatus,
            JointFeedback,
            MotoMotionReply,
            MotoJointFeedbackEx,
        ),
        Port.IO: _table(*_IO_BIT_GROUP_REQUESTS, MotoReadMRegister, MotoWriteMRegister),
        Port.STATE: _table(),  # the state server never reads its sockets (§2.3)
    }
)
"""Server side: what a client may send on each port, by msg_type."""

REPLY_CLASSES: Final[Mapping[Port, Mapping[int, type[Message]]]] = MappingProxyType(
    {
        Port.MOTION: _table(
            PingReply, MotoMotionReply, MotoGetDhParametersReply, *_IO_BIT_GROUP_REPLIES
        ),
        Port.STATE: _table(RobotStatus, JointFeedback, MotoJointFeedbackEx),
        Port.IO: _table(
            *_IO_BIT_GROUP_REPLIES, MotoReadMRegisterReply, MotoWriteMRegisterReply, IoErrorReply
        ),
    }
)
"""Client side: what the controller sends on each port, by msg_type."""

# Plain dicts of bound ``unpack`` methods for the hot path (Enum attribute access and
# MappingProxyType lookups cost more than the decoding of a small body).
_Unpack: TypeAlias = Callable[[bytes, ByteOrder], Message]


def _unpackers(table: Mapping[int, type[Message]]) -> dict[int, _Unpack]:
    return {msg_type: cls.unpack for msg_type, cls in table.items()}


_UnpackFrom: TypeAlias = Callable[[bytes, int, int, ByteOrder], Message]


def _unpackers_from(table: Mapping[int, type[Message]]) -> dict[int, _UnpackFrom]:
    return {msg_type: cls.unpack_from for msg_type, cls in table.items()}


_REQ_MOTION_FROM: Final = _unpackers_from(REQUEST_CLASSES[Port.MOTION])
_REQ_IO_FROM: Final = _unpackers_from(REQUEST_CLASSES[Port.IO])
_REQ_STATE_FROM: Final = _unpackers_from(REQUEST_CLASSES[Port.STATE])
_REP_MOTION_FROM: Final = _unpackers_from(REPLY_CLASSES[Port.MOTION])
_REP_IO_FROM: Final = _unpackers_from(REPLY_CLASSES[Port.IO])
_REP_STATE_FROM: Final = _unpackers_from(REPLY_CLASSES[Port.STATE])
_MOTION: Final = Port.MOTION
_STATE: Final = Port.STATE
_REQ_MOTION: Final = _unpackers(REQUEST_CLASSES[Port.MOTION])
_REQ_IO: Final = _unpackers(REQUEST_CLASSES[Port.IO])
_REQ_STATE: Final = _unpackers(REQUEST_CLASSES[Port.STATE])
_REP_MOTION: Final = _unpackers(REPLY_CLASSES[Port.MOTION])
_REP_IO: Final = _unpackers(REPLY_CLASSES[Port.IO])
_REP_STATE: Final = _unpackers(REPLY_CLASSES[Port.STATE])


def decode_request(frame: Frame, order: ByteOrder, port: Port) -> WireMessage:
    """Server side: the typed request in ``frame`` received on ``port``.

    Types the port does not know become :class:`UnknownMessage` (answer 3003).
    A body whose size differs from the type's raises :class:`RemoteProtocolError`;
    servers that follow MotoROS's size rules call :func:`sizes.check_request`
    instead, which trims surplus bytes and answers short ones.
    """
    msg_type, _, _, body = frame
    unpack = (_REQ_MOTION if port is _MOTION else _REQ_STATE if port is _STATE else _REQ_IO).get(
        msg_type
    )
    if unpack is None:
        return UnknownMessage(msg_type, body)
    return unpack(body, order)


def decode_reply(frame: Frame, order: ByteOrder, port: Port) -> WireMessage:
    """Client side: the typed reply or state topic in ``frame`` received on ``port``.

    Types the port does not know become :class:`UnknownMessage`; a body of the
    wrong size raises :class:`RemoteProtocolError` (MotoROS sends exact sizes).
    """
    msg_type, _, _, body = frame
    unpack = (_REP_STATE if port is _STATE else _REP_MOTION if port is _MOTION else _REP_IO).get(
        msg_type
    )
    if unpack is None:
        return UnknownMessage(msg_type, body)
    return unpack(body, order)
