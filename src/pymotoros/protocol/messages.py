"""One immutable class per Simple Message body, exactly as MotoROS 1.9.12 lays it out.

Why classes and not dicts: a message that exists is a message that can be sent.
Construction checks what would make the bytes impossible (an array that is not
10 floats long, an integer outside int32/uint32), so the servers and the client
never discover a bad field halfway through a ``send``. Decoding does *not* check
meaning: every integer stays a plain ``int`` because MotoROS itself accepts any
value on the wire and answers nonsense with a result code (the server must be
able to say INVALID/3004 to group 9, which it cannot if decoding refuses it).

``pack(order)`` returns the body only; the header and length prefix are the
business of :mod:`pymotoros.protocol.framing`. ``unpack(body, order)`` wants the
exact body size; trimming surplus bytes the MotoROS way is the job of
:mod:`pymotoros.protocol.sizes`.

Decoding is on the hot path (the state stream is 40 Hz × groups × clients, and
the client decodes every frame). Each message is therefore a ``NamedTuple``
underneath, behind a :class:`Message` mixin: ``unpack`` builds it with one
``tuple.__new__`` and no validation (the ``struct`` format already guarantees
every shape that validation would check). A frozen slotted dataclass filled
slot by slot measured clearly slower on JOINT_FEEDBACK (docs/benchmarks.md).
The mixin makes equality typed (``Ping() != PingReply()``, a message never
equals a plain tuple) and every message truthy; like any NamedTuple, messages
also offer ``_replace`` and ``_asdict`` (``_replace`` skips validation).
Layouts: reference §1.3 and §1.4.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Final, NamedTuple, Self, TypeAlias, TypeVar, cast

from pymotoros.errors import LocalProtocolError, RemoteProtocolError
from pymotoros.protocol.constants import (
    INT32_MAX,
    INT32_MIN,
    MAX_DH_LINKS,
    MAX_GROUPS,
    MAX_JOINTS,
    UINT32_MAX,
    ByteOrder,
    MsgType,
    ValidFields,
)

__all__ = [
    "BODY_SIZE_DH_REPLY",
    "BODY_SIZE_FEEDBACK_EX",
    "BODY_SIZE_FULL_EX_HEAD",
    "BODY_SIZE_GROUP_RECORD",
    "BODY_SIZE_MOTION_REPLY",
    "BODY_SIZE_TRAJ_PT_FULL",
    "ZERO_JOINTS",
    "DhLink",
    "IoErrorReply",
    "JointFeedback",
    "JointTrajPtExData",
    "JointTrajPtFull",
    "Message",
    "MotoGetDhParameters",
    "MotoGetDhParametersReply",
    "MotoJointFeedbackEx",
    "MotoJointTrajPtFullEx",
    "MotoMotionCtrl",
    "MotoMotionReply",
    "MotoReadIoBit",
    "MotoReadIoBitReply",
    "MotoReadIoGroup",
    "MotoReadIoGroupReply",
    "MotoReadMRegister",
    "MotoReadMRegisterReply",
    "MotoSelectTool",
    "MotoWriteIoBit",
    "MotoWriteIoBitReply",
    "MotoWriteIoGroup",
    "MotoWriteIoGroupReply",
    "MotoWriteMRegister",
    "MotoWriteMRegisterReply",
    "Ping",
    "PingReply",
    "RobotStatus",
    "Role",
    "UnknownMessage",
    "WireMessage",
]

# --------------------------------------------------------------------------- ranges and sizes


BODY_SIZE_GROUP_RECORD: Final = 132
"""groupNo, validFields, time, pos[10], vel[10], acc[10]: JOINT_FEEDBACK body and the
per-group record of FULL_EX / FEEDBACK_EX (§1.4)."""

BODY_SIZE_TRAJ_PT_FULL: Final = 136
"""groupNo, sequence, validFields, time, pos[10], vel[10], acc[10] (§1.4)."""

BODY_SIZE_FULL_EX_HEAD: Final = 8
"""numberOfValidGroups + sequence in front of the FULL_EX records (§1.4)."""

BODY_SIZE_FEEDBACK_EX: Final = 4 + MAX_GROUPS * BODY_SIZE_GROUP_RECORD
"""532: numberOfValidGroups + always four 132-byte slots (§1.3)."""

BODY_SIZE_MOTION_REPLY: Final = 60
"""groupNo, sequence, command, result, subcode, data[10] (§1.4)."""

BODY_SIZE_DH_REPLY: Final = MAX_GROUPS * MAX_DH_LINKS * 4 * 4
"""512: 4 groups × 8 links × {theta, d, a, alpha} float32 (§1.4)."""

ZERO_JOINTS: Final[tuple[float, ...]] = (0.0,) * MAX_JOINTS
"""A 10-slot float array of zeros: the unused ``data[]`` of motion messages, unused slots."""


class Role(enum.Enum):
    """Which way a message travels; it decides the default header (§1.2)."""

    REQUEST = "request"
    """Client → controller: comm SERVICE_REQUEST, reply INVALID."""
    REPLY = "reply"
    """Controller → client answer: comm SERVICE_REPLY, reply SUCCESS (or FAILURE)."""
    TOPIC = "topic"
    """State stream, nobody answers: comm TOPIC, reply INVALID."""


class _Kind(enum.Enum):
    """Wire type of one field, for construction-time checks and the generic codec."""

    I32 = "i"
    U32 = "I"
    F32 = "f"
    JOINTS = f"{MAX_JOINTS}f"


_I32, _U32, _F32, _JOINTS = _Kind.I32, _Kind.U32, _Kind.F32, _Kind.JOINTS

_T = TypeVar("_T")

if TYPE_CHECKING:

    def _tnew(cls: type[_T], values: Iterable[Any], /) -> _T:
        """Typed view of ``tuple.__new__`` (see below)."""

else:
    # Builds a message from its field values without validation (decode path only).
    # Typed above as returning ``cls``'s instance, so that decoders need no runtime
    # ``typing.cast`` call (a Python-level call per message on the hot path).
    _tnew = tuple.__new__

_AnyTuple: TypeAlias = tuple[Any, ...]
"""For ``cast``: naming the alias once avoids building ``tuple[Any, ...]`` on every call."""


def _structs(body_format: str) -> tuple[struct.Struct, struct.Struct]:
    """The (little-endian, big-endian) ``Struct`` pair for one body layout."""
    return struct.Struct(ByteOrder.LITTLE + body_format), struct.Struct(ByteOrder.BIG + body_format)


def _pick(pair: tuple[struct.Struct, struct.Struct], order: ByteOrder) -> struct.Struct:
    """Select the Struct for ``order`` (a plain ``==`` on the struct prefix: cheap)."""
    return pair[1] if order == ">" else pair[0]


def _size_error(cls: type, body: bytes, expected: int | str) -> RemoteProtocolError:
    return RemoteProtocolError(
        f"{cls.__name__}: body of {len(body)} bytes, expected {expected}", data=bytes(body)
    )


def _check_int(owner: str, name: str, value: object, kind: _Kind) -> None:
    if not isinstance(value, int):
        raise LocalProtocolError(f"{owner}.{name} must be an int, not {type(value).__name__}")
    low, high = (INT32_MIN, INT32_MAX) if kind is _I32 else (0, UINT32_MAX)
    if not low <= value <= high:
        kind_name = "int32" if kind is _I32 else "uint32"
        raise LocalProtocolError(f"{owner}.{name} = {value} does not fit in {kind_name}")


def _check_float(owner: str, name: str, value: object) -> None:
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise LocalProtocolError(f"{owner}.{name} must be a float, not {type(value).__name__}")
    try:
        struct.pack("<f", value)
    except OverflowError:
        raise LocalProtocolError(f"{owner}.{name} = {value} does not fit in float32") from None


def _pad_joints(owner: str, name: str, values: Iterable[float] | None) -> tuple[float, ...]:
    """Pad a short joint list with zeros to the 10 slots of the wire."""
    if values is None:
        return ZERO_JOINTS
    padded = tuple(values)
    if len(padded) > MAX_JOINTS:
        raise LocalProtocolError(f"{owner}: {name} has {len(padded)} values, at most {MAX_JOINTS}")
    return padded + ZERO_JOINTS[len(padded) :]


# --------------------------------------------------------------------------- base class


class Message:
    """Mixin of every typed message body (put it *first* in the bases).

    A message class is ``class X(Message, _XFields)`` where ``_XFields`` is a
    ``NamedTuple`` of the body's fields in wire order; ``X`` declares
    ``MSG_TYPE``, ``ROLE`` and ``FIELDS`` (name and wire kind of each field).
    Construction validates (``LocalProtocolError``) and turns joint lists into
    tuples; fixed-size bodies get ``pack``/``unpack`` from here.
    """

    __slots__ = ()

    MSG_TYPE: ClassVar[MsgType]
    ROLE: ClassVar[Role]
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = ()
    BODY_SIZE: ClassVar[int] = 0
    """Body bytes for fixed layouts (the minimum for FULL_EX)."""
    IO_RESULT: ClassVar[bool] = False
    """True for IO replies: their header says FAILURE when ``result_code`` is non-zero."""

    _STRUCTS: ClassVar[tuple[struct.Struct, struct.Struct]]
    _FLAT: ClassVar[bool] = True
    """No array field: the struct's values are the tuple's values."""

    if not TYPE_CHECKING:  # mypy keeps the typed NamedTuple constructor

        def __new__(cls, *args, **kwargs):
            return cls._validated(super().__new__(cls, *args, **kwargs))

    @classmethod
    def _validated(cls, message: Self) -> Self:
        """Check every field; return the message with joint arrays as tuples."""
        owner = cls.__name__
        values = list(cast(_AnyTuple, message))
        changed = False
        for index, (name, kind) in enumerate(cls.FIELDS):
            value = values[index]
            if kind is _JOINTS:
                joints = tuple(value)
                if len(joints) != MAX_JOINTS:
                    raise LocalProtocolError(
                        f"{owner}.{name} has {len(joints)} values; the wire carries exactly "
                        f"{MAX_JOINTS} (use for_joints() to pad)"
                    )
                for slot, item in enumerate(joints):
                    _check_float(owner, f"{name}[{slot}]", item)
                if joints is not value:
                    values[index] = joints
                    changed = True
            elif kind is _F32:
                _check_float(owner, name, value)
            else:
                _check_int(owner, name, value, kind)
        return _tnew(cls, values) if changed else message

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and tuple.__eq__(cast(_AnyTuple, self), other)

    def __ne__(self, other: object) -> bool:
        return not self == other

    def __hash__(self) -> int:
        return tuple.__hash__(cast(_AnyTuple, self))

    def __bool__(self) -> bool:
        """A message is a message, even with an empty body (tuples would say False)."""
        return True

    def _flat(self) -> list[Any]:
        flat: list[Any] = []
        for (_name, kind), value in zip(self.FIELDS, cast(_AnyTuple, self), strict=True):
            if kind is _JOINTS:
                flat.extend(value)
            else:
                flat.append(value)
        return flat

    def pack(self, order: ByteOrder) -> bytes:
        """The body bytes in ``order`` (no prefix, no header)."""
        layout = _pick(self._STRUCTS, order)
        try:
            if self._FLAT:
                return layout.pack(*cast(_AnyTuple, self))
            return layout.pack(*self._flat())
        except (struct.error, OverflowError, TypeError) as exc:  # only after _replace()
            raise LocalProtocolError(f"cannot pack {self!r}: {exc}") from None

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """Decode exactly one body of this type; a wrong size is the peer's fault."""
        layout = _pick(cls._STRUCTS, order)
        if len(body) != layout.size:
            raise _size_error(cls, body, layout.size)
        raw = layout.unpack(body)
        if cls._FLAT:
            return _tnew(cls, raw)
        values: list[object] = []
        index = 0
        for _name, kind in cls.FIELDS:
            if kind is _JOINTS:
                values.append(raw[index : index + MAX_JOINTS])
                index += MAX_JOINTS
            else:
                values.append(raw[index])
                index += 1
        return _tnew(cls, values)

    @classmethod
    def unpack_from(cls, buffer: bytes, start: int, end: int, order: ByteOrder) -> Self:
        """``unpack(buffer[start:end])``; hot types override it to skip the slice copy."""
        return cls.unpack(buffer[start:end], order)

    @classmethod
    def _bind_unpack_from(cls, order: ByteOrder) -> Callable[[bytes, int, int], Message]:
        """``unpack_from`` with ``order`` fixed, for the decoders' per-order tables.

        Decoding is the same; only the per-message work that depends on the byte
        order alone (``order == ">"``, picking the ``Struct``, looking up its
        method) moves out of the hot path into this call, made once per type and
        order at import. Flat fixed layouts decoded by :meth:`Message.unpack` get
        a closure over their ``Struct``; the hot JOINT_FEEDBACK and
        JOINT_TRAJ_PT_FULL override this; any other type calls its own
        :meth:`unpack_from`.
        """
        if cls._FLAT and cls.unpack.__func__ is Message.unpack.__func__:  # type: ignore[attr-defined]
            layout = _pick(cls._STRUCTS, order)
            size = layout.size
            unpack_fields = layout.unpack_from  # bound once: no attribute lookup per message

            def unpack_flat(buffer: bytes, start: int, end: int) -> Message:
                if end - start != size:
                    raise _size_error(cls, buffer[start:end], size)
                return _tnew(cls, unpack_fields(buffer, start))

            return unpack_flat

        unpack_from = cls.unpack_from

        def unpack_other(buffer: bytes, start: int, end: int) -> Message:
            return unpack_from(buffer, start, end, order)

        return unpack_other


def _register(cls: type[Message]) -> None:
    """Derive the Structs of a fixed-layout message class from its ``FIELDS``."""
    cls._STRUCTS = _structs("".join(kind.value for _name, kind in cls.FIELDS))
    cls.BODY_SIZE = cls._STRUCTS[0].size
    cls._FLAT = all(kind is not _JOINTS for _name, kind in cls.FIELDS)


# --------------------------------------------------------------------------- field tuples
# The NamedTuples below only hold fields; messages sharing a layout share one.


class DhLink(NamedTuple):
    """Denavit–Hartenberg parameters of one link, as MotoROS reports them."""

    theta: float
    d: float
    a: float
    alpha: float


class _NoFields(NamedTuple):
    pass


class _Status(NamedTuple):
    drives_powered: int
    e_stopped: int
    error_code: int
    in_error: int
    in_motion: int
    mode: int
    motion_possible: int


class _GroupRecord(NamedTuple):
    group_no: int
    valid_fields: int
    time: float
    pos: tuple[float, ...]
    vel: tuple[float, ...]
    acc: tuple[float, ...] = ZERO_JOINTS


class _Point(NamedTuple):
    group_no: int
    sequence: int
    valid_fields: int
    time: float
    pos: tuple[float, ...]
    vel: tuple[float, ...]
    acc: tuple[float, ...] = ZERO_JOINTS


class _Ctrl(NamedTuple):
    group_no: int
    sequence: int
    command: int
    data: tuple[float, ...] = ZERO_JOINTS


class _Reply(NamedTuple):
    group_no: int
    sequence: int
    command: int
    result: int
    subcode: int
    data: tuple[float, ...] = ZERO_JOINTS


class _Tool(NamedTuple):
    group_no: int
    tool: int
    sequence: int


class _Address(NamedTuple):
    io_address: int


class _AddressValue(NamedTuple):
    io_address: int
    io_value: int


class _ValueResult(NamedTuple):
    value: int
    result_code: int


class _Result(NamedTuple):
    result_code: int


class _Register(NamedTuple):
    register_number: int


class _RegisterValue(NamedTuple):
    register_number: int
    value: int


class _ErrorReply(NamedTuple):
    result: int
    subcode: int


class _Dh(NamedTuple):
    groups: tuple[tuple[DhLink, ...], ...]


class _FullEx(NamedTuple):
    number_of_valid_groups: int
    sequence: int
    groups: tuple[JointTrajPtExData, ...]


class _FeedbackEx(NamedTuple):
    number_of_valid_groups: int
    groups: tuple[JointFeedback, ...]


_I32_FIELDS_ERROR: Final = (("result", _I32), ("subcode", _I32))


# --------------------------------------------------------------------------- ping


class Ping(Message, _NoFields):
    """PING request (type 1, empty body); MotoROS answers with an empty PING reply."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.PING
    ROLE: ClassVar[Role] = Role.REQUEST


class PingReply(Message, _NoFields):
    """The PING reply: same type 1, comm SERVICE_REPLY, reply SUCCESS, empty body."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.PING
    ROLE: ClassVar[Role] = Role.REPLY


# --------------------------------------------------------------------------- state topics


class RobotStatus(Message, _Status):
    """ROBOT_STATUS (13): seven int32 status fields, sent every state cycle (§2.6).

    Tri-state fields are 1/0 (-1 "unknown" only for a rare ``in_motion``);
    ``mode`` is 1 (manual/teach) or 2 (auto/play).
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.ROBOT_STATUS
    ROLE: ClassVar[Role] = Role.TOPIC
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = tuple(
        (name, _I32) for name in _Status._fields
    )


_GROUP_RECORD_FIELDS: Final[tuple[tuple[str, _Kind], ...]] = (
    ("group_no", _I32),
    ("valid_fields", _I32),
    ("time", _F32),
    ("pos", _JOINTS),
    ("vel", _JOINTS),
    ("acc", _JOINTS),
)

_RECORD_POS_AT: Final = 12
_RECORD_VEL_AT: Final = 52
_RECORD_ACC_AT: Final = 92
"""Offsets of pos, vel and acc in the 132-byte group record (§1.4)."""


class JointFeedback(Message, _GroupRecord):
    """JOINT_FEEDBACK (15): one group's feedback position (rad or m) and speed.

    MotoROS sends ``valid_fields`` 6 (position + velocity), ``time`` 0.0 and ``acc``
    zeros (§2.4). Arrays are in ROS joint order, 10 slots, slots 8 and 9 zero.
    The same 132-byte layout is one slot of JOINT_FEEDBACK_EX.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.JOINT_FEEDBACK
    ROLE: ClassVar[Role] = Role.TOPIC
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = _GROUP_RECORD_FIELDS

    @classmethod
    def for_joints(
        cls,
        group_no: int,
        pos: Iterable[float],
        vel: Iterable[float] | None = None,
        *,
        time: float = 0.0,
        acc: Iterable[float] | None = None,
        valid_fields: int | None = None,
    ) -> Self:
        """Build from joint lists of any length ≤ 10 (zero-padded).

        ``valid_fields`` defaults to what MotoROS sends: POSITION, plus VELOCITY
        when ``vel`` is given.
        """
        if valid_fields is None:
            valid_fields = ValidFields.POSITION | (ValidFields.VELOCITY if vel is not None else 0)
        name = cls.__name__
        return cls(
            group_no,
            int(valid_fields),
            time,
            _pad_joints(name, "pos", pos),
            _pad_joints(name, "vel", vel),
            _pad_joints(name, "acc", acc),
        )

    def pack(self, order: ByteOrder) -> bytes:
        """Hand-unrolled: the state server packs one per group every cycle."""
        group_no, valid_fields, time, pos, vel, acc = self
        try:
            return (_RECORD_BE if order == ">" else _RECORD_LE).pack(
                group_no, valid_fields, time, *pos, *vel, *acc
            )
        except (struct.error, OverflowError, TypeError) as exc:  # only after _replace()
            raise LocalProtocolError(f"cannot pack {self!r}: {exc}") from None

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        return cls.unpack_from(body, 0, len(body), order)

    @classmethod
    def unpack_from(cls, buffer: bytes, start: int, end: int, order: ByteOrder) -> Self:
        """Hot path of the state stream: hand-unrolled, no validation (see module doc).

        Three 10-float unpacks are cheaper than one 33-value unpack plus slicing.
        """
        if end - start != BODY_SIZE_GROUP_RECORD:
            raise _size_error(cls, buffer[start:end], BODY_SIZE_GROUP_RECORD)
        if order == ">":
            head, joints = _RECORD_HEAD_BE, _JOINTS_BE
        else:
            head, joints = _RECORD_HEAD_LE, _JOINTS_LE
        group_no, valid_fields, time = head.unpack_from(buffer, start)
        return _tnew(
            cls,
            (
                group_no,
                valid_fields,
                time,
                joints.unpack_from(buffer, start + _RECORD_POS_AT),
                joints.unpack_from(buffer, start + _RECORD_VEL_AT),
                joints.unpack_from(buffer, start + _RECORD_ACC_AT),
            ),
        )

    @classmethod
    def _bind_unpack_from(cls, order: ByteOrder) -> Callable[[bytes, int, int], JointFeedback]:
        """:meth:`unpack_from` for one byte order: the client's per-frame work on the state port.

        Same decoding; the Structs' bound methods are picked once here, so each
        message costs no byte-order test and no attribute lookup.
        """
        head, joints = (
            (_RECORD_HEAD_BE, _JOINTS_BE) if order == ">" else (_RECORD_HEAD_LE, _JOINTS_LE)
        )
        unpack_head = head.unpack_from
        unpack_joints = joints.unpack_from

        def unpack_feedback(buffer: bytes, start: int, end: int) -> JointFeedback:
            if end - start != BODY_SIZE_GROUP_RECORD:
                raise _size_error(cls, buffer[start:end], BODY_SIZE_GROUP_RECORD)
            group_no, valid_fields, time = unpack_head(buffer, start)
            return _tnew(
                cls,
                (
                    group_no,
                    valid_fields,
                    time,
                    unpack_joints(buffer, start + _RECORD_POS_AT),
                    unpack_joints(buffer, start + _RECORD_VEL_AT),
                    unpack_joints(buffer, start + _RECORD_ACC_AT),
                ),
            )

        return unpack_feedback


_register(JointFeedback)
_RECORD_LE, _RECORD_BE = JointFeedback._STRUCTS
_RECORD_HEAD_LE, _RECORD_HEAD_BE = _structs("iif")  # groupNo, validFields, time
_JOINTS_LE, _JOINTS_BE = _structs(_JOINTS.value)


class JointTrajPtExData(Message, _GroupRecord):
    """One group's record inside JOINT_TRAJ_PT_FULL_EX: a point without its own sequence.

    Not a message on its own (``MSG_TYPE`` is that of the carrying FULL_EX); the
    layout is the 132-byte group record of §1.4.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = _GROUP_RECORD_FIELDS

    @classmethod
    def for_joints(
        cls,
        group_no: int,
        time: float,
        pos: Iterable[float],
        vel: Iterable[float],
        acc: Iterable[float] | None = None,
        *,
        valid_fields: int | None = None,
    ) -> Self:
        """Build from joint lists of any length ≤ 10; flags default to time+pos+vel(+acc)."""
        if valid_fields is None:
            valid_fields = _point_flags(acc)
        name = cls.__name__
        return cls(
            group_no,
            int(valid_fields),
            time,
            _pad_joints(name, "pos", pos),
            _pad_joints(name, "vel", vel),
            _pad_joints(name, "acc", acc),
        )


_register(JointTrajPtExData)


def _point_flags(acc: object) -> int:
    flags = ValidFields.TIME | ValidFields.POSITION | ValidFields.VELOCITY
    return int(flags | ValidFields.ACCELERATION if acc is not None else flags)


# --------------------------------------------------------------------------- motion requests

_POINT_POS_AT: Final = 16
_POINT_VEL_AT: Final = 56
_POINT_ACC_AT: Final = 96
"""Offsets of pos, vel and acc in the JOINT_TRAJ_PT_FULL body (§1.4)."""


class JointTrajPtFull(Message, _Point):
    """JOINT_TRAJ_PT_FULL (14): one trajectory point for one group (§3.4).

    MotoROS needs ``valid_fields`` to contain TIME, POSITION and VELOCITY (else
    3015) and ignores ``acc``. Arrays are in ROS joint order (rad or m, rad/s or
    m/s); ``time`` is seconds from the trajectory start.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.JOINT_TRAJ_PT_FULL
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (
        ("group_no", _I32),
        ("sequence", _I32),
        ("valid_fields", _I32),
        ("time", _F32),
        ("pos", _JOINTS),
        ("vel", _JOINTS),
        ("acc", _JOINTS),
    )

    @classmethod
    def for_joints(
        cls,
        group_no: int,
        sequence: int,
        time: float,
        pos: Iterable[float],
        vel: Iterable[float],
        acc: Iterable[float] | None = None,
        *,
        valid_fields: int | None = None,
    ) -> Self:
        """Build from joint lists of any length ≤ 10; flags default to time+pos+vel(+acc)."""
        if valid_fields is None:
            valid_fields = _point_flags(acc)
        name = cls.__name__
        return cls(
            group_no,
            sequence,
            int(valid_fields),
            time,
            _pad_joints(name, "pos", pos),
            _pad_joints(name, "vel", vel),
            _pad_joints(name, "acc", acc),
        )

    def pack(self, order: ByteOrder) -> bytes:
        """Hand-unrolled: the client packs one per trajectory point."""
        group_no, sequence, valid_fields, time, pos, vel, acc = self
        try:
            return (_POINT_BE if order == ">" else _POINT_LE).pack(
                group_no, sequence, valid_fields, time, *pos, *vel, *acc
            )
        except (struct.error, OverflowError, TypeError) as exc:  # only after _replace()
            raise LocalProtocolError(f"cannot pack {self!r}: {exc}") from None

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        return cls.unpack_from(body, 0, len(body), order)

    @classmethod
    def unpack_from(cls, buffer: bytes, start: int, end: int, order: ByteOrder) -> Self:
        """Hot path of the motion server: hand-unrolled, no validation (see module doc)."""
        if end - start != BODY_SIZE_TRAJ_PT_FULL:
            raise _size_error(cls, buffer[start:end], BODY_SIZE_TRAJ_PT_FULL)
        if order == ">":
            head, joints = _POINT_HEAD_BE, _JOINTS_BE
        else:
            head, joints = _POINT_HEAD_LE, _JOINTS_LE
        group_no, sequence, valid_fields, time = head.unpack_from(buffer, start)
        return _tnew(
            cls,
            (
                group_no,
                sequence,
                valid_fields,
                time,
                joints.unpack_from(buffer, start + _POINT_POS_AT),
                joints.unpack_from(buffer, start + _POINT_VEL_AT),
                joints.unpack_from(buffer, start + _POINT_ACC_AT),
            ),
        )

    @classmethod
    def _bind_unpack_from(cls, order: ByteOrder) -> Callable[[bytes, int, int], JointTrajPtFull]:
        """:meth:`unpack_from` for one byte order: the motion server's per-point work."""
        head, joints = (
            (_POINT_HEAD_BE, _JOINTS_BE) if order == ">" else (_POINT_HEAD_LE, _JOINTS_LE)
        )
        unpack_head = head.unpack_from
        unpack_joints = joints.unpack_from

        def unpack_point(buffer: bytes, start: int, end: int) -> JointTrajPtFull:
            if end - start != BODY_SIZE_TRAJ_PT_FULL:
                raise _size_error(cls, buffer[start:end], BODY_SIZE_TRAJ_PT_FULL)
            group_no, sequence, valid_fields, time = unpack_head(buffer, start)
            return _tnew(
                cls,
                (
                    group_no,
                    sequence,
                    valid_fields,
                    time,
                    unpack_joints(buffer, start + _POINT_POS_AT),
                    unpack_joints(buffer, start + _POINT_VEL_AT),
                    unpack_joints(buffer, start + _POINT_ACC_AT),
                ),
            )

        return unpack_point


_register(JointTrajPtFull)
_POINT_LE, _POINT_BE = JointTrajPtFull._STRUCTS
_POINT_HEAD_LE, _POINT_HEAD_BE = _structs("iiif")  # groupNo, sequence, validFields, time


class MotoMotionCtrl(Message, _Ctrl):
    """MOTO_MOTION_CTRL (2001): a motion command (:class:`MotionCommand`) for a group.

    ``data`` is ignored by MotoROS; ``command`` stays an int so that an unknown
    code can be decoded and answered.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_MOTION_CTRL
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (
        ("group_no", _I32),
        ("sequence", _I32),
        ("command", _I32),
        ("data", _JOINTS),
    )


_register(MotoMotionCtrl)


class MotoMotionReply(Message, _Reply):
    """MOTO_MOTION_REPLY (2002): the answer to every motion-port request.

    ``command`` echoes the request's command (MOTION_CTRL) or its msg_type; the
    outcome is ``result`` + ``subcode`` (the header always says SUCCESS, §1.2).
    For CHECK_QUEUE_CNT the count travels in ``subcode``.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_MOTION_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (
        ("group_no", _I32),
        ("sequence", _I32),
        ("command", _I32),
        ("result", _I32),
        ("subcode", _I32),
        ("data", _JOINTS),
    )


_register(MotoMotionReply)


class MotoSelectTool(Message, _Tool):
    """MOTO_SELECT_TOOL (2018). Field order on the wire is groupNo, tool, sequence."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_SELECT_TOOL
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (
        ("group_no", _I32),
        ("tool", _I32),
        ("sequence", _I32),
    )


_register(MotoSelectTool)


class MotoGetDhParameters(Message, _NoFields):
    """MOTO_GET_DH_PARAMETERS (2020) request: empty body."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_GET_DH_PARAMETERS
    ROLE: ClassVar[Role] = Role.REQUEST


_cls: type[Message]
for _cls in (Ping, PingReply, RobotStatus, MotoGetDhParameters):
    _register(_cls)


_ZERO_LINK: Final = DhLink(0.0, 0.0, 0.0, 0.0)
_FLOATS_PER_LINK: Final = 4


class MotoGetDhParametersReply(Message, _Dh):
    """The GET_DH_PARAMETERS reply (type 2020 again): 4 groups × 8 links, always.

    Groups the controller does not have are all zero (§1.4).
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_GET_DH_PARAMETERS
    ROLE: ClassVar[Role] = Role.REPLY
    BODY_SIZE: ClassVar[int] = BODY_SIZE_DH_REPLY

    @classmethod
    def _validated(cls, message: Self) -> Self:
        owner = cls.__name__
        groups = tuple(message.groups)
        if len(groups) != MAX_GROUPS:
            raise LocalProtocolError(
                f"{owner}: {len(groups)} groups, the wire carries exactly {MAX_GROUPS} "
                "(use for_groups() to pad)"
            )
        checked: list[tuple[DhLink, ...]] = []
        for g, links in enumerate(groups):
            row = tuple(DhLink(*link) for link in links)
            if len(row) != MAX_DH_LINKS:
                raise LocalProtocolError(
                    f"{owner}: group {g} has {len(row)} links, exactly {MAX_DH_LINKS} expected"
                )
            for k, link in enumerate(row):
                for name, value in zip(DhLink._fields, link, strict=True):
                    _check_float(owner, f"groups[{g}][{k}].{name}", value)
            checked.append(row)
        return _tnew(cls, (tuple(checked),))

    @classmethod
    def for_groups(cls, groups: Iterable[Iterable[Sequence[float]]]) -> Self:
        """Pad the existing groups (each ≤ 8 links of 4 floats) with zero links and groups."""
        rows: list[tuple[DhLink, ...]] = []
        for links in groups:
            row = tuple(DhLink(*link) for link in links)
            rows.append(row + (_ZERO_LINK,) * (MAX_DH_LINKS - len(row)))
        zero_group = (_ZERO_LINK,) * MAX_DH_LINKS
        return cls(tuple(rows) + (zero_group,) * (MAX_GROUPS - len(rows)))

    def pack(self, order: ByteOrder) -> bytes:
        flat = [value for links in self.groups for link in links for value in link]
        return _pick(_DH_STRUCTS, order).pack(*flat)

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        if len(body) != BODY_SIZE_DH_REPLY:
            raise _size_error(cls, body, BODY_SIZE_DH_REPLY)
        raw = _pick(_DH_STRUCTS, order).unpack(body)
        step = _FLOATS_PER_LINK
        per_group = MAX_DH_LINKS * step
        groups = tuple(
            tuple(
                DhLink(*raw[base + k * step : base + (k + 1) * step]) for k in range(MAX_DH_LINKS)
            )
            for base in range(0, MAX_GROUPS * per_group, per_group)
        )
        return _tnew(cls, (groups,))


_DH_STRUCTS: Final = _structs(f"{MAX_GROUPS * MAX_DH_LINKS * _FLOATS_PER_LINK}f")


# --------------------------------------------------------------------------- multi-group


def _group_count(n: int) -> int:
    """How many 132-byte records a message with ``numberOfValidGroups = n`` carries."""
    return min(max(n, 0), MAX_GROUPS)


def _check_records(owner: str, n: int, groups: tuple[object, ...], kind: type) -> None:
    _check_int(owner, "number_of_valid_groups", n, _I32)
    if len(groups) != _group_count(n):
        raise LocalProtocolError(
            f"{owner}: number_of_valid_groups {n} needs {_group_count(n)} records, "
            f"got {len(groups)}"
        )
    if not all(isinstance(g, kind) for g in groups):
        raise LocalProtocolError(f"{owner}.groups must hold {kind.__name__} records")


class MotoJointTrajPtFullEx(Message, _FullEx):
    """MOTO_JOINT_TRAJ_PT_FULL_EX (2016): one point for several groups, one sequence.

    The body is 8 + 132·n bytes. ``number_of_valid_groups`` is kept as sent
    (MotoROS answers n ≤ 0 or a bad group itself), so ``groups`` holds
    ``clamp(n, 0, 4)`` records. Use :meth:`for_groups` to set n from the records.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    ROLE: ClassVar[Role] = Role.REQUEST
    BODY_SIZE: ClassVar[int] = BODY_SIZE_FULL_EX_HEAD

    @classmethod
    def _validated(cls, message: Self) -> Self:
        owner = cls.__name__
        groups = tuple(message.groups)
        _check_records(owner, message.number_of_valid_groups, groups, JointTrajPtExData)
        _check_int(owner, "sequence", message.sequence, _I32)
        return _tnew(cls, (message.number_of_valid_groups, message.sequence, groups))

    @classmethod
    def for_groups(cls, sequence: int, groups: Iterable[JointTrajPtExData]) -> Self:
        """n = the number of records given (at most 4)."""
        records = tuple(groups)
        if len(records) > MAX_GROUPS:
            raise LocalProtocolError(f"{cls.__name__}: {len(records)} groups, at most {MAX_GROUPS}")
        return cls(len(records), sequence, records)

    def pack(self, order: ByteOrder) -> bytes:
        head = _pick(_EX_HEAD_STRUCTS, order).pack(self.number_of_valid_groups, self.sequence)
        return head + b"".join(record.pack(order) for record in self.groups)

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """Exactly 8 + 132·clamp(n, 0, 4) bytes (sizes.py trims MotoROS's padded 552)."""
        head = _pick(_EX_HEAD_STRUCTS, order)
        if len(body) < head.size:
            raise _size_error(cls, body, f"at least {head.size}")
        n, sequence = head.unpack_from(body)
        count = _group_count(n)
        expected = head.size + count * BODY_SIZE_GROUP_RECORD
        if len(body) != expected:
            raise _size_error(cls, body, f"{expected} for numberOfValidGroups {n}")
        records = tuple(
            JointTrajPtExData.unpack(body[start : start + BODY_SIZE_GROUP_RECORD], order)
            for start in range(head.size, expected, BODY_SIZE_GROUP_RECORD)
        )
        return _tnew(cls, (n, sequence, records))


_EX_HEAD_STRUCTS: Final = _structs("ii")


class MotoJointFeedbackEx(Message, _FeedbackEx):
    """MOTO_JOINT_FEEDBACK_EX (2017): every group's feedback in one message.

    Always 4 slots on the wire (532-byte body); slots past ``groups`` are zero.
    ``groups`` holds ``clamp(n, 0, 4)`` :class:`JointFeedback` records.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_JOINT_FEEDBACK_EX
    ROLE: ClassVar[Role] = Role.TOPIC
    BODY_SIZE: ClassVar[int] = BODY_SIZE_FEEDBACK_EX

    @classmethod
    def _validated(cls, message: Self) -> Self:
        groups = tuple(message.groups)
        _check_records(cls.__name__, message.number_of_valid_groups, groups, JointFeedback)
        return _tnew(cls, (message.number_of_valid_groups, groups))

    @classmethod
    def for_groups(cls, groups: Iterable[JointFeedback]) -> Self:
        """n = the number of records given (at most 4)."""
        records = tuple(groups)
        if len(records) > MAX_GROUPS:
            raise LocalProtocolError(f"{cls.__name__}: {len(records)} groups, at most {MAX_GROUPS}")
        return cls(len(records), records)

    def pack(self, order: ByteOrder) -> bytes:
        head = _pick(_EX_COUNT_STRUCTS, order).pack(self.number_of_valid_groups)
        slots = b"".join(record.pack(order) for record in self.groups)
        return head + slots + bytes(BODY_SIZE_FEEDBACK_EX - len(head) - len(slots))

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        if len(body) != BODY_SIZE_FEEDBACK_EX:
            raise _size_error(cls, body, BODY_SIZE_FEEDBACK_EX)
        head = _pick(_EX_COUNT_STRUCTS, order)
        (n,) = head.unpack_from(body)
        end = head.size + _group_count(n) * BODY_SIZE_GROUP_RECORD
        records = tuple(
            JointFeedback.unpack_from(body, start, start + BODY_SIZE_GROUP_RECORD, order)
            for start in range(head.size, end, BODY_SIZE_GROUP_RECORD)
        )
        return _tnew(cls, (n, records))


_EX_COUNT_STRUCTS: Final = _structs("i")


# --------------------------------------------------------------------------- IO


class MotoReadIoBit(Message, _Address):
    """MOTO_READ_IO_BIT (2003): read one bit at ``io_address`` (IO port, or motion port)."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_BIT
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("io_address", _U32),)


class MotoReadIoBitReply(Message, _ValueResult):
    """MOTO_READ_IO_BIT_REPLY (2004): ``value`` 0/1 and an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_BIT_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("value", _U32), ("result_code", _U32))


class MotoWriteIoBit(Message, _AddressValue):
    """MOTO_WRITE_IO_BIT (2005): write 0/1 to ``io_address``."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_BIT
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("io_address", _U32), ("io_value", _U32))


class MotoWriteIoBitReply(Message, _Result):
    """MOTO_WRITE_IO_BIT_REPLY (2006): an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_BIT_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("result_code", _U32),)


class MotoReadIoGroup(Message, _Address):
    """MOTO_READ_IO_GROUP (2007): read 8 bits; ``io_address`` is a byte number n (bits n·10+k)."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_GROUP
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("io_address", _U32),)


class MotoReadIoGroupReply(Message, _ValueResult):
    """MOTO_READ_IO_GROUP_REPLY (2008): ``value`` 0..255 (bit 0 = LSB) and a result code."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_GROUP_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("value", _U32), ("result_code", _U32))


class MotoWriteIoGroup(Message, _AddressValue):
    """MOTO_WRITE_IO_GROUP (2009): write ``io_value`` (≤ 0xFF) to byte ``io_address``."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_GROUP
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("io_address", _U32), ("io_value", _U32))


class MotoWriteIoGroupReply(Message, _Result):
    """MOTO_WRITE_IO_GROUP_REPLY (2010): an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_GROUP_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("result_code", _U32),)


class MotoReadMRegister(Message, _Register):
    """MOTO_READ_MREGISTER (2012, IO port only): ``register_number`` M000..M999 (or +1000000)."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_MREGISTER
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("register_number", _U32),)


class MotoReadMRegisterReply(Message, _ValueResult):
    """Reply to READ_MREGISTER: reuses type 2012; a 16-bit ``value`` and a result code."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_MREGISTER
    ROLE: ClassVar[Role] = Role.REPLY
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("value", _U32), ("result_code", _U32))


class MotoWriteMRegister(Message, _RegisterValue):
    """MOTO_WRITE_MREGISTER (2013, IO port only): write ``value`` (≤ 0xFFFF), M000..M559."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_MREGISTER
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (
        ("register_number", _U32),
        ("value", _U32),
    )


class MotoWriteMRegisterReply(Message, _Result):
    """Reply to WRITE_MREGISTER: reuses type 2013; an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_MREGISTER
    ROLE: ClassVar[Role] = Role.REPLY
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = (("result_code", _U32),)


_IO_ERROR_PADDING: Final = BODY_SIZE_MOTION_REPLY - 8
"""Zero bytes after result and subcode in the IO error reply (60-byte body, §1.6)."""


class IoErrorReply(Message, _ErrorReply):
    """The IO port's answer to an unknown type (3003) or a short message (3001).

    MotoROS sends it as type 2002 with the shape of a MOTION_REPLY, but with
    ``result`` at body offset 0 and ``subcode`` at 4 and the rest zero (§1.6).
    Only meaningful on the IO port; on the motion port type 2002 is a
    :class:`MotoMotionReply`.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_MOTION_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    FIELDS: ClassVar[tuple[tuple[str, _Kind], ...]] = _I32_FIELDS_ERROR

    def pack(self, order: ByteOrder) -> bytes:
        return _pick(self._STRUCTS, order).pack(self.result, self.subcode) + bytes(
            _IO_ERROR_PADDING
        )

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """60 bytes; the trailing 52 are not checked (MotoROS leaves them zero)."""
        if len(body) != BODY_SIZE_MOTION_REPLY:
            raise _size_error(cls, body, BODY_SIZE_MOTION_REPLY)
        return _tnew(cls, _pick(cls._STRUCTS, order).unpack_from(body))


for _cls in (
    MotoReadIoBit,
    MotoReadIoBitReply,
    MotoWriteIoBit,
    MotoWriteIoBitReply,
    MotoReadIoGroup,
    MotoReadIoGroupReply,
    MotoWriteIoGroup,
    MotoWriteIoGroupReply,
    MotoReadMRegister,
    MotoReadMRegisterReply,
    MotoWriteMRegister,
    MotoWriteMRegisterReply,
    IoErrorReply,
):
    _register(_cls)
IoErrorReply.BODY_SIZE = BODY_SIZE_MOTION_REPLY


# --------------------------------------------------------------------------- unknown


@dataclass(frozen=True, slots=True)
class UnknownMessage:
    """A frame whose type this port does not know; kept raw so a server can answer 3003.

    ``encode`` sends it as a request, which is how tests and tools provoke the
    unknown-type path (e.g. GET_VERSION, type 2).
    """

    ROLE: ClassVar[Role] = Role.REQUEST
    IO_RESULT: ClassVar[bool] = False

    msg_type: int
    body: bytes = field(default=b"")

    def __post_init__(self) -> None:
        _check_int(type(self).__name__, "msg_type", self.msg_type, _I32)
        object.__setattr__(self, "body", bytes(self.body))

    def pack(self, order: ByteOrder) -> bytes:
        """The raw body: it is already bytes, byte order does not apply."""
        return self.body


WireMessage: TypeAlias = Message | UnknownMessage
"""Anything the decoders return and ``encode`` accepts."""
