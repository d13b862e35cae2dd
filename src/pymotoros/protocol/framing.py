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
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final, NamedTuple, TypeAlias, cast, overload

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
    REPLY_CLASSES,
    REQUEST_CLASSES,
    Message,
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
    "prefix_fits",
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


def prefix_fits(data: bytes, order: ByteOrder) -> bool:
    """Whether ``data`` starts with a legal length prefix when read in ``order``: how a
    recording tells its byte order, and how the client guesses a wrong ``--controller``."""
    if len(data) < PREFIX_SIZE:
        return False
    length: int = (_PREFIX_BE if order == ">" else _PREFIX_LE).unpack_from(data)[0]
    return MIN_LENGTH_PREFIX <= length <= MAX_LENGTH_PREFIX


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


_ClassHeader: TypeAlias = tuple[int, int, bool, "int | None"]
"""(default comm type, default reply type, IO_RESULT, msg_type or None for UnknownMessage)."""

_CLASS_HEADERS: Final[dict[type, _ClassHeader]] = {}
"""Per message class, what :func:`encode` derives from the class alone: filled on first
use, so a frame costs one dict lookup on the class instead of a ``Role`` lookup (Enum
hashing is a Python call) and attribute reads."""


def _class_header(message: WireMessage) -> _ClassHeader:
    comm, reply = _DEFAULT_HEADER[message.ROLE]
    msg_type = None if isinstance(message, UnknownMessage) else int(message.MSG_TYPE)
    return int(comm), int(reply), bool(message.IO_RESULT), msg_type


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
    cls = type(message)
    known = _CLASS_HEADERS.get(cls)
    if known is None:
        known = _CLASS_HEADERS[cls] = _class_header(message)
    default_comm, default_reply, io_result, class_msg_type = known
    if reply_type is None:
        reply_type = default_reply
        if io_result and getattr(message, "result_code", 0) != 0:
            reply_type = ReplyType.FAILURE
    if comm_type is None:
        comm_type = default_comm
    msg_type = cast(UnknownMessage, message).msg_type if class_msg_type is None else class_msg_type
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

    __slots__ = (
        "_buf",
        "_order",
        "_pos",
        "_rep_io",
        "_rep_motion",
        "_rep_state",
        "_req_io",
        "_req_motion",
        "_req_state",
        "_unpack_head",
        "_unpack_prefix",
        "comm_type",
    )

    def __init__(self, order: ByteOrder) -> None:
        self._order = order
        big = order == ">"
        # Everything that depends on the byte order alone is chosen here, once: the
        # hot paths below then do no ``order`` comparison, no table selection by
        # order and no ``Struct`` method lookup per frame (each costs a few % of a
        # JOINT_FEEDBACK decode).
        self._unpack_head = (_HEAD_BE if big else _HEAD_LE).unpack_from
        self._unpack_prefix = (_PREFIX_BE if big else _PREFIX_LE).unpack_from
        tables = _BOUND_BE if big else _BOUND_LE
        self._req_motion = tables.req_motion
        self._req_io = tables.req_io
        self._req_state = tables.req_state
        self._rep_motion = tables.rep_motion
        self._rep_io = tables.rep_io
        self._rep_state = tables.rep_state
        self._buf = b""
        self._pos = 0
        self.comm_type = 0
        """The header's comm type of the last frame returned (0 before the first): what
        :meth:`next_reply` leaves out, for a client that tells topics from replies
        without the two-step form's :class:`Frame` and body copy. A plain attribute,
        not a property: the client reads it for every frame."""

    @property
    def order(self) -> ByteOrder:
        """The byte order frames are decoded in (big-endian for an FS100)."""
        return self._order

    @property
    def buffered(self) -> int:
        """Bytes received but not yet returned as frames (a partial frame at most, normally)."""
        return len(self._buf) - self._pos

    def feed(self, data: bytes | bytearray | memoryview) -> None:
        """Append received bytes; nothing is parsed until :meth:`next_frame`."""
        if not self._buf:
            # Nothing pending (the normal case): keep the chunk itself, no copy for bytes.
            # Every method that consumes the last buffered byte resets ``_buf`` to b"" and
            # ``_pos`` to 0, so an empty ``_buf`` is the whole test (cheaper than comparing
            # ``_pos`` with ``len(_buf)``) and ``_pos`` is already 0.
            self._buf = data if type(data) is bytes else bytes(data)
            return
        if self._pos:
            self._buf = self._buf[self._pos :]
            self._pos = 0
        self._buf += data

    @overload
    def _next(self, table: None) -> Frame | None: ...

    @overload
    def _next(self, table: Mapping[int, _BoundUnpackFrom]) -> WireMessage | None: ...

    def _next(self, table: Mapping[int, _BoundUnpackFrom] | None) -> Frame | WireMessage | None:
        """The framing every ``next_*`` method shares, and the one place the buffer advances.

        Consumes the next whole frame and returns it as a :class:`Frame` when
        ``table`` is None, else decoded by ``table``'s bound decoder for its type
        (:class:`UnknownMessage` for a type not in it); None if more bytes are
        needed. One routine with a switch rather than a framing helper returning
        a tuple: one call and no tuple per frame is what keeps ``next_reply``
        fast now that JOINT_FEEDBACK has a single decoder (bench/bench_codec.py).
        """
        buf = self._buf
        pos = self._pos
        size = len(buf)
        if size - pos >= FRAME_OVERHEAD:
            # hot path: prefix and header in one unpack
            length, msg_type, comm_type, reply_type = self._unpack_head(buf, pos)
        elif size - pos >= PREFIX_SIZE:
            (length,) = self._unpack_prefix(buf, pos)
        else:
            return None
        if length < MIN_LENGTH_PREFIX or length > MAX_LENGTH_PREFIX:
            raise RemoteProtocolError(
                f"length prefix {length} outside {MIN_LENGTH_PREFIX}..{MAX_LENGTH_PREFIX}",
                data=buf[pos : pos + MAX_WIRE_MESSAGE_SIZE],
            )
        end = pos + PREFIX_SIZE + length
        if end > size:
            # A prefix alone never gets past here: a legal length ends after the header.
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
        self.comm_type = comm_type
        if table is None:
            return _new_frame(Frame, (msg_type, comm_type, reply_type, buf[start:end]))
        unpack_from = table.get(msg_type)
        if unpack_from is None:
            return UnknownMessage(msg_type, buf[start:end])
        return unpack_from(buf, start, end)

    def next_frame(self) -> Frame | None:
        """The next whole frame, or None if more bytes are needed."""
        return self._next(None)

    def next_reply(self, port: Port) -> WireMessage | None:
        """:meth:`next_frame` then :func:`decode_reply` in one step: the client's hot path.

        Faster because no :class:`Frame` or body copy is made; the header's comm
        and reply types are not returned (use the two-step form to inspect them).
        A frame whose body does not fit its type is consumed, then reported as
        :class:`RemoteProtocolError`.
        """
        return self._next(
            self._rep_state  # first: the state stream is what a client receives most
            if port is _STATE
            else self._rep_motion
            if port is _MOTION
            else self._rep_io
        )

    def next_request(self, port: Port) -> WireMessage | None:
        """:meth:`next_frame` then :func:`decode_request` in one step (exact sizes only).

        Servers that follow MotoROS's size rules use :meth:`next_frame` and
        :func:`sizes.check_request` instead.
        """
        return self._next(
            self._req_motion
            if port is _MOTION
            else self._req_state
            if port is _STATE
            else self._req_io
        )

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


_BoundUnpackFrom: TypeAlias = Callable[[bytes, int, int], Message]
"""A class's ``unpack_from`` with the byte order fixed: ``(buffer, start, end) -> message``."""


@dataclass(frozen=True, slots=True)
class _BoundTables:
    """Plain dicts msg_type -> bound decoder, per port and role, for one byte order.

    Plain dicts because Enum attribute access and MappingProxyType lookups cost
    more than the decoding of a small body; pre-bound to the byte order so the
    hot path does not test it per message (see ``Message._bind_unpack_from``).
    A slotted class, not a NamedTuple: Python 3.11 specialises slot reads, not
    NamedTuple field reads, and ``decode_reply`` reads one per frame.
    """

    req_motion: dict[int, _BoundUnpackFrom]
    req_io: dict[int, _BoundUnpackFrom]
    req_state: dict[int, _BoundUnpackFrom]
    rep_motion: dict[int, _BoundUnpackFrom]
    rep_io: dict[int, _BoundUnpackFrom]
    rep_state: dict[int, _BoundUnpackFrom]


def _bound_tables(order: ByteOrder) -> _BoundTables:
    def bind(table: Mapping[int, type[Message]]) -> dict[int, _BoundUnpackFrom]:
        return {msg_type: cls._bind_unpack_from(order) for msg_type, cls in table.items()}

    return _BoundTables(
        req_motion=bind(REQUEST_CLASSES[Port.MOTION]),
        req_io=bind(REQUEST_CLASSES[Port.IO]),
        req_state=bind(REQUEST_CLASSES[Port.STATE]),
        rep_motion=bind(REPLY_CLASSES[Port.MOTION]),
        rep_io=bind(REPLY_CLASSES[Port.IO]),
        rep_state=bind(REPLY_CLASSES[Port.STATE]),
    )


_BOUND_LE: Final = _bound_tables(ByteOrder.LITTLE)
_BOUND_BE: Final = _bound_tables(ByteOrder.BIG)
_MOTION: Final = Port.MOTION
_STATE: Final = Port.STATE


def decode_request(frame: Frame, order: ByteOrder, port: Port) -> WireMessage:
    """Server side: the typed request in ``frame`` received on ``port``.

    Types the port does not know become :class:`UnknownMessage` (answer 3003).
    A body whose size differs from the type's raises :class:`RemoteProtocolError`;
    servers that follow MotoROS's size rules call :func:`sizes.check_request`
    instead, which trims surplus bytes and answers short ones.
    """
    msg_type, _, _, body = frame
    tables = _BOUND_BE if order == ">" else _BOUND_LE
    unpack_from = (
        tables.req_motion
        if port is _MOTION
        else tables.req_state
        if port is _STATE
        else tables.req_io
    ).get(msg_type)
    if unpack_from is None:
        return UnknownMessage(msg_type, body)
    return unpack_from(body, 0, len(body))


def decode_reply(frame: Frame, order: ByteOrder, port: Port) -> WireMessage:
    """Client side: the typed reply or state topic in ``frame`` received on ``port``.

    Types the port does not know become :class:`UnknownMessage`; a body of the
    wrong size raises :class:`RemoteProtocolError` (MotoROS sends exact sizes).
    """
    msg_type, _, _, body = frame
    tables = _BOUND_BE if order == ">" else _BOUND_LE
    unpack_from = (
        tables.rep_state
        if port is _STATE
        else tables.rep_motion
        if port is _MOTION
        else tables.rep_io
    ).get(msg_type)
    if unpack_from is None:
        return UnknownMessage(msg_type, body)
    return unpack_from(body, 0, len(body))
