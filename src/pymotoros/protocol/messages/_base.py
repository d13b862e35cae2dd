"""The machinery every message class shares: field kinds, checks, the codec and the registry.

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

Each class says once what it is (:class:`Message` explains the class
variables) and :meth:`Message.__init_subclass__` does the rest: it derives the
``Struct`` pair and the body size from ``FIELDS`` and enters the class in
:data:`REQUEST_CLASSES` / :data:`REPLY_CLASSES`, which the decoders in
``framing`` and the size rules in ``sizes`` are built from. Layouts: reference
§1.3 and §1.4.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar, Final, NamedTuple, Self, TypeAlias, TypeVar, cast

from pymotoros.errors import LocalProtocolError, RemoteProtocolError
from pymotoros.protocol.constants import (
    INT32_MAX,
    INT32_MIN,
    MAX_JOINTS,
    UINT32_MAX,
    ByteOrder,
    MsgType,
    Port,
)

__all__ = [
    "REPLY_CLASSES",
    "REQUEST_CLASSES",
    "ZERO_JOINTS",
    "Message",
    "Role",
    "UnknownMessage",
    "WireMessage",
]

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


class Kind(enum.Enum):
    """Wire type of one field, for construction-time checks and the generic codec."""

    I32 = "i"
    U32 = "I"
    F32 = "f"
    JOINTS = f"{MAX_JOINTS}f"


I32, U32, F32, JOINTS = Kind.I32, Kind.U32, Kind.F32, Kind.JOINTS

_T = TypeVar("_T")

if TYPE_CHECKING:

    def tnew(cls: type[_T], values: Iterable[Any], /) -> _T:
        """Typed view of ``tuple.__new__`` (see below)."""

else:
    # Builds a message from its field values without validation (decode path only).
    # Typed above as returning ``cls``'s instance, so that decoders need no runtime
    # ``typing.cast`` call (a Python-level call per message on the hot path).
    tnew = tuple.__new__

_AnyTuple: TypeAlias = tuple[Any, ...]
"""For ``cast``: naming the alias once avoids building ``tuple[Any, ...]`` on every call."""

if TYPE_CHECKING:

    def _tuple_eq(left: object, right: object, /) -> bool:
        """Typed view of ``tuple.__eq__`` (see below)."""

    def _tuple_hash(value: object, /) -> int:
        """Typed view of ``tuple.__hash__`` (see below)."""

else:
    # Message equality and hashing are the tuple's, without a runtime ``cast`` call each
    # (the motion server hashes every request it receives).
    _tuple_eq = tuple.__eq__
    _tuple_hash = tuple.__hash__


_ECHO_NONE: Final = 0
"""Not a request with a sequence: its MOTION_REPLY matches by type alone (reply_echo)."""
_ECHO_TYPE: Final = 1
"""The reply echoes (msg_type, sequence)."""
_ECHO_COMMAND: Final = 2
"""The reply echoes (command, sequence): MOTION_CTRL."""


def struct_pair(body_format: str) -> tuple[struct.Struct, struct.Struct]:
    """The (little-endian, big-endian) ``Struct`` pair for one body layout."""
    return struct.Struct(ByteOrder.LITTLE + body_format), struct.Struct(ByteOrder.BIG + body_format)


def pick(pair: tuple[struct.Struct, struct.Struct], order: ByteOrder) -> struct.Struct:
    """Select the Struct for ``order`` (a plain ``==`` on the struct prefix: cheap)."""
    return pair[1] if order == ">" else pair[0]


def size_error(cls: type, body: bytes, expected: int | str) -> RemoteProtocolError:
    return RemoteProtocolError(
        f"{cls.__name__}: body of {len(body)} bytes, expected {expected}", data=bytes(body)
    )


def check_int(owner: str, name: str, value: object, kind: Kind) -> None:
    if not isinstance(value, int):
        raise LocalProtocolError(f"{owner}.{name} must be an int, not {type(value).__name__}")
    low, high = (INT32_MIN, INT32_MAX) if kind is I32 else (0, UINT32_MAX)
    if not low <= value <= high:
        kind_name = "int32" if kind is I32 else "uint32"
        raise LocalProtocolError(f"{owner}.{name} = {value} does not fit in {kind_name}")


def check_float(owner: str, name: str, value: object) -> None:
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise LocalProtocolError(f"{owner}.{name} must be a float, not {type(value).__name__}")
    try:
        struct.pack("<f", value)
    except OverflowError:
        raise LocalProtocolError(f"{owner}.{name} = {value} does not fit in float32") from None


_FIELD_TYPE: Final[Mapping[Kind, type]] = MappingProxyType(
    {I32: int, U32: int, F32: float, JOINTS: tuple}
)
"""The exact type per kind the quick stage of a check vouches for (a bool, an int for a
float, a list or a subclass are valid too: the field-by-field stage takes them)."""

_JOINT_VALUE_TYPES: Final = frozenset((float, int))


def _as_is(message: _T) -> _T:
    """The check of a layout without fields: nothing to check."""
    return message


def bind_check(cls: type[Message]) -> Callable[[Any], Any]:
    """The one check of ``cls``'s ``FIELDS``: ``check(message)`` returns the message (joint
    arrays as tuples) or raises :class:`LocalProtocolError` naming its first bad field.

    Why it is quick: the state server builds JOINT_FEEDBACK and ROBOT_STATUS every cycle
    and the client builds a JOINT_TRAJ_PT_FULL per point; checking their 31 floats one
    Python call each was a tenth of a streamed move's time. So the types are compared in
    one ``tuple(map(type, …))`` against the layout's exact types, and the ranges are
    tested by ``struct`` packing, which is what :func:`check_float` and
    :func:`check_int` test (float32 overflow; int32/uint32 range for an exact ``int``).
    A message that passes is returned as it is. Anything else, a refusal or an unusual
    valid value (a bool, a list, a numpy float), is walked in wire order by
    :func:`walk_fields`, the one place the errors are worded.
    """
    fields = cls.FIELDS
    if not fields:
        return _as_is
    owner = cls.__name__
    signature = tuple(_FIELD_TYPE[kind] for _name, kind in fields)
    scalar_at = tuple(i for i, (_name, kind) in enumerate(fields) if kind is not JOINTS)
    joints_at = tuple(i for i, (_name, kind) in enumerate(fields) if kind is JOINTS)
    pack_scalars = struct.Struct(
        ByteOrder.LITTLE + "".join(fields[i][1].value for i in scalar_at)
    ).pack
    pack_joints = struct.Struct(ByteOrder.LITTLE + JOINTS.value).pack
    value_types = _JOINT_VALUE_TYPES
    size = MAX_JOINTS
    count = len(scalar_at)
    leading = scalar_at == tuple(range(count))  # scalars first: every layout so far

    def check(message: _AnyTuple) -> Any:
        if tuple(map(type, message)) == signature:
            try:
                pack_scalars(*(message[:count] if leading else [message[i] for i in scalar_at]))
                for i in joints_at:
                    values = message[i]
                    if len(values) != size or not value_types.issuperset(map(type, values)):
                        break
                    pack_joints(*values)
                else:
                    return message
            except (struct.error, OverflowError):
                pass
        return walk_fields(cls, owner, fields, message)

    return check


def walk_fields(
    cls: type[_T], owner: str, fields: tuple[tuple[str, Kind], ...], message: Any
) -> _T:
    """Field by field in wire order: joint arrays made tuples, the first bad field
    refused in words (:func:`check_float`, :func:`check_int`). What :func:`bind_check`'s
    quick stage could not vouch for comes here."""
    values = list(message)
    changed = False
    for index, (name, kind) in enumerate(fields):
        value = values[index]
        if kind is JOINTS:
            joints = tuple(value)
            if len(joints) != MAX_JOINTS:
                raise LocalProtocolError(
                    f"{owner}.{name} has {len(joints)} values; the wire carries exactly "
                    f"{MAX_JOINTS} (use for_joints() to pad)"
                )
            for slot, item in enumerate(joints):
                check_float(owner, f"{name}[{slot}]", item)
            if joints is not value:
                values[index] = joints
                changed = True
        elif kind is F32:
            check_float(owner, name, value)
        else:
            check_int(owner, name, value, kind)
    return tnew(cls, values) if changed else cast(_T, message)


def pad_joints(owner: str, name: str, values: Iterable[float] | None) -> tuple[float, ...]:
    """Pad a short joint list with zeros to the 10 slots of the wire."""
    if values is None:
        return ZERO_JOINTS
    padded = tuple(values)
    if len(padded) > MAX_JOINTS:
        raise LocalProtocolError(f"{owner}: {name} has {len(padded)} values, at most {MAX_JOINTS}")
    return padded + ZERO_JOINTS[len(padded) :]


def pad_arrays(
    owner: str,
    pos: Iterable[float] | None,
    vel: Iterable[float] | None,
    acc: Iterable[float] | None,
) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """``pos``, ``vel`` and ``acc`` padded to the wire's 10 slots (:func:`pad_joints`):
    the three arrays of every joint record (feedback, trajectory point, FULL_EX slot)."""
    return (
        pad_joints(owner, "pos", pos),
        pad_joints(owner, "vel", vel),
        pad_joints(owner, "acc", acc),
    )


def bind_joint_record(
    cls: type[_T], head: struct.Struct, joints: struct.Struct, size: int
) -> Callable[[bytes, int, int], _T]:
    """The decoder of a joint record: ``head`` (the int and float fields), then pos, vel
    and acc as 10 float32 each; ``size`` bytes in all (the three arrays end it).

    JOINT_FEEDBACK (the client's per-frame work) and JOINT_TRAJ_PT_FULL (the motion
    server's per-point work) both decode here. Hand-unrolled, no validation: three
    10-float unpacks are cheaper than one unpack plus slicing, and the Structs' bound
    methods and the offsets are picked once here, so a record costs no byte-order test
    and no attribute or global lookup.
    """
    unpack_head = head.unpack_from
    unpack_joints = joints.unpack_from
    acc_at = size - joints.size
    vel_at = acc_at - joints.size
    pos_at = vel_at - joints.size

    def unpack_record(buffer: bytes, start: int, end: int) -> _T:
        if end - start != size:
            raise size_error(cls, buffer[start:end], size)
        # Concatenation, not (*head, …): one tuple add instead of a list built and copied.
        return tnew(
            cls,
            unpack_head(buffer, start)  # noqa: RUF005
            + (
                unpack_joints(buffer, start + pos_at),
                unpack_joints(buffer, start + vel_at),
                unpack_joints(buffer, start + acc_at),
            ),
        )

    return unpack_record


# --------------------------------------------------------------------------- base class


class Message:
    """Mixin of every typed message body (put it *first* in the bases).

    A message class is ``class X(Message, _XFields)`` where ``_XFields`` is a
    ``NamedTuple`` of the body's fields in wire order. ``X`` says once, as class
    variables, everything the codec needs:

    - ``MSG_TYPE``: its :class:`MsgType` (every wire code lives in constants.py);
    - ``ROLE``: which way it travels, hence its default header;
    - ``REQUEST_ON``: the ports whose server decodes it from a client, and
      ``REPLY_ON``: the ports on which a client decodes it from the controller
      (both empty for a record that only travels inside another message);
    - ``FIELDS``: name and wire kind of each field. The ``Struct`` pair,
      ``BODY_SIZE`` and the field ``OFFSETS`` follow from it; a class with a
      hand-written layout declares ``BODY_SIZE`` (and ``OFFSETS``) itself, and
      ``FIXED_SIZE = False`` when its size depends on its content.

    :meth:`__init_subclass__` derives the rest and enters the class in
    :data:`REQUEST_CLASSES` / :data:`REPLY_CLASSES`; a second class for the same
    type, port and direction is a ``TypeError`` at import. Why this hook and not
    a metaclass or a decorator: ``typing.NamedTuple`` accepts no other base, so
    the fields cannot inherit registration; but the mixin is first in every
    message's MRO, so its ``__init_subclass__`` sees each class as it is made,
    adds nothing to decoding (it runs at import only), and unlike a decorator
    cannot be forgotten. Only what a class declares in its *own* body is
    registered, so subclassing a message never registers it twice.

    Construction validates (``LocalProtocolError``) and turns joint lists into
    tuples; fixed-size bodies get ``pack``/``unpack`` from here.
    """

    __slots__ = ()

    MSG_TYPE: ClassVar[MsgType]
    ROLE: ClassVar[Role]
    REQUEST_ON: ClassVar[tuple[Port, ...]] = ()
    """Ports on which a server decodes this class from what a client sent (decode_request)."""
    REPLY_ON: ClassVar[tuple[Port, ...]] = ()
    """Ports on which a client decodes this class from what the controller sent (decode_reply)."""
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = ()
    BODY_SIZE: ClassVar[int] = 0
    """Body bytes: derived from ``FIELDS`` unless declared (the minimum for FULL_EX)."""
    FIXED_SIZE: ClassVar[bool] = True
    """False when the body size depends on the body (FULL_EX: 8 + 132·n)."""
    OFFSETS: ClassVar[Mapping[str, int]] = MappingProxyType({})
    """Body offset of each scalar field (``sizes`` reads a short body's sequence there)."""
    IO_RESULT: ClassVar[bool] = False
    """True for IO replies: their header says FAILURE when ``result_code`` is non-zero."""

    _STRUCTS: ClassVar[tuple[struct.Struct, struct.Struct]]
    _FLAT: ClassVar[bool] = True
    """No array field: the struct's values are the tuple's values."""
    _DECODERS: ClassVar[dict[str, Callable[[bytes, int, int], Any]]]
    """``_bind_unpack_from(order)`` per byte order, made on first use (see unpack_from)."""
    _ECHO: ClassVar[int]
    """What :meth:`reply_echo` reads, decided once from ``ROLE`` and ``OFFSETS``."""
    _ARITY: ClassVar[int] = -1
    """How many fields the NamedTuple has: all given by position, construction skips its
    generated ``__new__`` (a Python call that only packs them into the tuple)."""
    _LEADING: ClassVar[int] = -1
    """With every joint array after every scalar field, how many scalars lead; else -1."""
    _CHECK: ClassVar[Callable[[Any], Any]]
    """The class's one construction check: :func:`bind_check` of its ``FIELDS``, or
    its own :meth:`_validated` (hand-laid layouts)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Derive the layout from ``FIELDS`` and register the class (see the class doc)."""
        super().__init_subclass__(**kwargs)
        own = cls.__dict__
        cls._STRUCTS = struct_pair("".join(kind.value for _name, kind in cls.FIELDS))
        cls._FLAT = all(kind is not JOINTS for _name, kind in cls.FIELDS)
        cls._DECODERS = {}
        # A class with its own _validated (a hand-laid layout) is checked by it alone.
        own_check = cls._validated.__func__ is not Message._validated.__func__  # type: ignore[attr-defined]
        cls._CHECK = cls._validated if own_check else bind_check(cls)
        cls._ARITY = len(getattr(cls, "_fields", ()))
        kinds = [kind for _name, kind in cls.FIELDS]
        leading = kinds.index(JOINTS) if JOINTS in kinds else len(kinds)
        cls._LEADING = leading if all(kind is JOINTS for kind in kinds[leading:]) else -1
        if "BODY_SIZE" not in own:
            cls.BODY_SIZE = cls._STRUCTS[0].size
        if "OFFSETS" not in own:
            cls.OFFSETS = field_offsets(cls.FIELDS)
        if getattr(cls, "ROLE", None) is not Role.REQUEST or "sequence" not in cls.OFFSETS:
            cls._ECHO = _ECHO_NONE
        else:
            cls._ECHO = _ECHO_COMMAND if "command" in cls.OFFSETS else _ECHO_TYPE
        entries = [
            (tables[port], port)
            for ports, tables in (
                (own.get("REQUEST_ON", ()), _REQUESTS),
                (own.get("REPLY_ON", ()), _REPLIES),
            )
            for port in ports
        ]
        for table, port in entries:  # every check before any entry: all or nothing
            known = table.get(int(cls.MSG_TYPE))
            if known is not None:
                raise TypeError(
                    f"{cls.__name__}: {cls.MSG_TYPE.name} on the {port.value} port is "
                    f"already {known.__name__}"
                )
        for table, _port in entries:
            table[int(cls.MSG_TYPE)] = cls

    if not TYPE_CHECKING:  # mypy keeps the typed NamedTuple constructor

        def __new__(cls, *args, **kwargs):
            if not kwargs and len(args) == cls._ARITY:  # every field given, by position:
                message = tnew(cls, args)  # what the NamedTuple's __new__ does
            else:
                message = super().__new__(cls, *args, **kwargs)
            return cls._CHECK(message)

    @classmethod
    def _validated(cls, message: Self) -> Self:
        """Check every field; return the message with joint arrays as tuples
        (:func:`bind_check`; a hand-laid layout overrides this)."""
        checked: Self = cls._CHECK(message)
        return checked

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and _tuple_eq(self, other)

    def __ne__(self, other: object) -> bool:
        return not self == other

    def __hash__(self) -> int:
        return _tuple_hash(self)

    def __bool__(self) -> bool:
        """A message is a message, even with an empty body (tuples would say False)."""
        return True

    def _flat(self) -> list[Any]:
        fields = cast(_AnyTuple, self)
        leading = self._LEADING
        flat: list[Any]
        if leading >= 0 and len(fields) == len(self.FIELDS):
            # Scalars then arrays (MOTION_CTRL, MOTION_REPLY): no per-field kind test.
            flat = list(fields[:leading])
            for value in fields[leading:]:
                flat.extend(value)
            return flat
        flat = []
        for (_name, kind), value in zip(self.FIELDS, cast(_AnyTuple, self), strict=True):
            if kind is JOINTS:
                flat.extend(value)
            else:
                flat.append(value)
        return flat

    def pack(self, order: ByteOrder) -> bytes:
        """The body bytes in ``order`` (no prefix, no header)."""
        layout = pick(self._STRUCTS, order)
        try:
            if self._FLAT:
                fields: _AnyTuple = self  # type: ignore[assignment]  # a tuple; cast is a call
                return layout.pack(*fields)
            return layout.pack(*self._flat())
        except (struct.error, OverflowError, TypeError) as exc:  # only after _replace()
            raise LocalProtocolError(f"cannot pack {self!r}: {exc}") from None

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """Decode exactly one body of this type; a wrong size is the peer's fault."""
        layout = pick(cls._STRUCTS, order)
        if len(body) != layout.size:
            raise size_error(cls, body, layout.size)
        raw = layout.unpack(body)
        if cls._FLAT:
            return tnew(cls, raw)
        values: list[object] = []
        index = 0
        for _name, kind in cls.FIELDS:
            if kind is JOINTS:
                values.append(raw[index : index + MAX_JOINTS])
                index += MAX_JOINTS
            else:
                values.append(raw[index])
                index += 1
        return tnew(cls, values)

    @classmethod
    def unpack_from(cls, buffer: bytes, start: int, end: int, order: ByteOrder) -> Self:
        """``unpack(buffer[start:end])``, through the same bound decoder the decoders use."""
        decoders = cls._DECODERS
        decode = decoders.get(order)
        if decode is None:
            decode = decoders[order] = cls._bind_unpack_from(order)
        return cast(Self, decode(buffer, start, end))

    def reply_echo(self) -> tuple[int, int] | None:
        """(command, sequence) the MOTO_MOTION_REPLY to this request must echo (§1.6), or None.

        Derived from the layout, so a new request needs no entry anywhere: a
        request with a ``sequence`` field is answered with its sequence and its
        ``command`` field (MOTION_CTRL) or else its type; any other message
        (no sequence, or not a request) matches by type alone.
        """
        echo = self._ECHO
        if echo == _ECHO_NONE:
            return None
        fields: Any = self
        command = fields.command if echo == _ECHO_COMMAND else self.MSG_TYPE
        return int(command), int(fields.sequence)

    @classmethod
    def needed_body_size(cls, body: bytes, order: ByteOrder) -> int:
        """Body bytes MotoROS wants for this type, given what arrived (§1.5).

        ``BODY_SIZE`` for fixed layouts; a class whose size depends on its
        content (``FIXED_SIZE = False``) overrides this.
        """
        return cls.BODY_SIZE

    @classmethod
    def _bind_unpack_from(cls, order: ByteOrder) -> Callable[[bytes, int, int], Message]:
        """The one decoder of this type for ``order``: ``(buffer, start, end) -> message``.

        Decoding is that of :meth:`unpack`; only the per-message work that
        depends on the byte order alone (``order == ">"``, picking the
        ``Struct``, looking up its method) moves out of the hot path into this
        call, made once per type and order (the decoders' tables at import,
        :meth:`unpack_from` on first use). Flat fixed layouts decoded by
        :meth:`Message.unpack` get a closure over their ``Struct``; the hot
        JOINT_FEEDBACK and JOINT_TRAJ_PT_FULL override this; any other type
        slices and calls its own :meth:`unpack`.
        """
        if cls._FLAT and cls.unpack.__func__ is Message.unpack.__func__:  # type: ignore[attr-defined]
            layout = pick(cls._STRUCTS, order)
            size = layout.size
            unpack_fields = layout.unpack_from  # bound once: no attribute lookup per message

            def unpack_flat(buffer: bytes, start: int, end: int) -> Message:
                if end - start != size:
                    raise size_error(cls, buffer[start:end], size)
                return tnew(cls, unpack_fields(buffer, start))

            return unpack_flat

        if cls._LEADING >= 0 and cls.unpack.__func__ is Message.unpack.__func__:  # type: ignore[attr-defined]
            return _bind_arrays_last(cls, order)

        unpack = cls.unpack

        def unpack_other(buffer: bytes, start: int, end: int) -> Message:
            return unpack(buffer[start:end], order)

        return unpack_other


def _bind_arrays_last(cls: type[Message], order: ByteOrder) -> Callable[[bytes, int, int], Message]:
    """:meth:`Message.unpack` of a layout whose joint arrays all follow its scalars, bound
    to ``order``: the scalars in one unpack, each array in one, no slicing of the body.

    MOTO_MOTION_REPLY (the answer to every point the client streams) decodes here.
    """
    kinds = [kind for _name, kind in cls.FIELDS]
    leading = cls._LEADING
    head = struct.Struct(order + "".join(kind.value for kind in kinds[:leading]))
    joints = struct.Struct(order + JOINTS.value)
    offsets = tuple(head.size + k * joints.size for k in range(len(kinds) - leading))
    size = pick(cls._STRUCTS, order).size
    unpack_head = head.unpack_from
    unpack_joints = joints.unpack_from

    def unpack_arrays_last(buffer: bytes, start: int, end: int) -> Message:
        if end - start != size:
            raise size_error(cls, buffer[start:end], size)
        return tnew(
            cls,
            unpack_head(buffer, start)
            + tuple([unpack_joints(buffer, start + at) for at in offsets]),
        )

    return unpack_arrays_last


def field_offsets(fields: tuple[tuple[str, Kind], ...]) -> Mapping[str, int]:
    """Body offset of each scalar field of a ``FIELDS`` layout (arrays are skipped)."""
    offsets: dict[str, int] = {}
    at = 0
    for name, kind in fields:
        if kind is not JOINTS:
            offsets[name] = at
        at += struct.calcsize(ByteOrder.LITTLE + kind.value)
    return MappingProxyType(offsets)


_REQUESTS: Final[dict[Port, dict[int, type[Message]]]] = {port: {} for port in Port}
_REPLIES: Final[dict[Port, dict[int, type[Message]]]] = {port: {} for port in Port}

REQUEST_CLASSES: Final[Mapping[Port, Mapping[int, type[Message]]]] = MappingProxyType(
    {port: MappingProxyType(table) for port, table in _REQUESTS.items()}
)
"""Server side: what a client may send on each port, by msg_type (filled from ``REQUEST_ON``).

The motion port also decodes 13/15/2002/2017: MotoROS sizes them and then
closes the connection (``sizes`` decides that; here we only decode). The state
server never reads its sockets (§2.3), so the state port's table stays empty.
"""

REPLY_CLASSES: Final[Mapping[Port, Mapping[int, type[Message]]]] = MappingProxyType(
    {port: MappingProxyType(table) for port, table in _REPLIES.items()}
)
"""Client side: what the controller sends on each port, by msg_type (filled from ``REPLY_ON``)."""


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
        check_int(type(self).__name__, "msg_type", self.msg_type, I32)
        object.__setattr__(self, "body", bytes(self.body))

    def pack(self, order: ByteOrder) -> bytes:
        """The raw body: it is already bytes, byte order does not apply."""
        return self.body


WireMessage: TypeAlias = Message | UnknownMessage
"""Anything the decoders return and ``encode`` accepts."""


class NoFields(NamedTuple):
    """The field tuple of an empty body (PING, the GET_DH_PARAMETERS request)."""
