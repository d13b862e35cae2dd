"""The codec's fast paths against the paths they shortcut: same messages, same errors.

* construction: ``Message._validated`` (a few C calls when every field is an exact,
  fitting int/float/tuple, else field by field) against the field-by-field definition
  (``tests/oracles/messages.py``), on random fields with NaN, infinities, subnormals,
  float32 overflow, int32/uint32 edges, bools, lists, wrong lengths and wrong types;
* decoding: ``FrameDecoder.next_reply`` plus its ``comm_type`` (what the client's read
  loop uses) against ``next_frame`` then ``decode_reply`` (what it used, and still uses
  with wire logging on), on random streams of right, wrong-size and unknown frames;
* encoding: :func:`encode` with its per-class header cache against the header derived
  from the message itself, as it was before the cache.
"""

from __future__ import annotations

import math
import random
import struct
from collections.abc import Callable
from functools import partial
from typing import Any

import pytest

from oracles.messages import validated_fields
from pymotoros.errors import LocalProtocolError, ProtocolError, RemoteProtocolError
from pymotoros.protocol.constants import (
    HEADER_SIZE,
    MAX_JOINTS,
    ByteOrder,
    CommType,
    Port,
    ReplyType,
)
from pymotoros.protocol.framing import (
    Frame,
    FrameDecoder,
    decode_reply,
    encode,
    encode_frame,
)
from pymotoros.protocol.messages import (
    JointFeedback,
    JointTrajPtFull,
    UnknownMessage,
    _base,
)
from pymotoros.protocol.messages._base import (
    F32,
    I32,
    JOINTS,
    REPLY_CLASSES,
    REQUEST_CLASSES,
    U32,
    Kind,
    Message,
    Role,
)
from pymotoros.protocol.messages.trajectory import JointTrajPtExData

F32_MAX = struct.unpack("<f", struct.pack("<I", 0x7F7FFFFF))[0]

FLOATS: tuple[object, ...] = (
    0.0,
    -0.0,
    1.5,
    -2.25,
    math.nan,
    -math.nan,
    math.inf,
    -math.inf,
    5e-324,  # float64 subnormal: float32 0
    1.4e-45,  # float32's smallest subnormal
    -1e-40,
    F32_MAX,
    -F32_MAX,
    3.4028235e38,  # just past float32's maximum: rounds to it
    3.4028236e38,  # past the rounding edge: overflow
    1e39,
    -1e300,
    7,  # an int where a float goes: valid, not the fast path
    -(2**31),
    10**400,  # an int too large for any float
    True,
    "1.0",
    None,
)

INTS: tuple[object, ...] = (
    0,
    1,
    -1,
    7,
    2**31 - 1,
    2**31,
    -(2**31),
    -(2**31) - 1,
    2**32 - 1,
    2**32,
    10**30,
    True,
    False,
    1.0,
    "3",
    None,
)


def _classes() -> list[type[Message]]:
    """Every class whose construction goes through the generic ``Message._validated``."""
    found: dict[str, type[Message]] = {}
    for tables in (REQUEST_CLASSES, REPLY_CLASSES):
        for table in tables.values():
            for cls in table.values():
                found[cls.__name__] = cls
    found[JointTrajPtExData.__name__] = JointTrajPtExData
    return [
        cls
        for _name, cls in sorted(found.items())
        if cls.FIELDS and "_validated" not in cls.__dict__
    ]


CLASSES = _classes()


def _good(kind: Kind, rng: random.Random) -> object:
    if kind is JOINTS:
        return tuple(rng.uniform(-4.0, 4.0) for _ in range(MAX_JOINTS))
    if kind is F32:
        return rng.uniform(-1e3, 1e3)
    if kind is I32:
        return rng.randint(-(2**31), 2**31 - 1)
    return rng.randint(0, 2**32 - 1)


def _odd(kind: Kind, rng: random.Random) -> object:
    if kind is JOINTS:
        choice = rng.randrange(6)
        size = MAX_JOINTS if choice < 4 else rng.choice((0, 6, 9, 11))
        values = [rng.choice(FLOATS) if rng.random() < 0.3 else rng.random() for _ in range(size)]
        if choice == 1:
            return values  # a list: valid when its values are, converted to a tuple
        if choice == 2:
            return iter(values) if rng.random() < 0.5 else "x" * size
        return tuple(values)
    if kind is F32:
        return rng.choice(FLOATS)
    return rng.choice(INTS)


def _outcome(check: Callable[[Any], Any], cls: type[Message], values: list[object]) -> object:
    message = tuple.__new__(cls, values)
    try:
        result = check(message)
    except Exception as exc:  # the very type and text are what is compared
        return ("raised", type(exc), str(exc))
    same = result is message
    return ("ok", type(result), _key(tuple(result)), same)


def _key(values: tuple[object, ...]) -> tuple[object, ...]:
    """Values compared so that NaN equals NaN and -0.0 differs from 0.0 (bit patterns)."""
    out: list[object] = []
    for v in values:
        if isinstance(v, tuple):
            out.append(_key(v))
        elif type(v) is float:
            out.append(("f", struct.pack("<d", v)))
        else:
            out.append((type(v), v))
    return tuple(out)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_fast_validation_equals_field_by_field(
    cls: type[Message], monkeypatch: pytest.MonkeyPatch
) -> None:
    walks = [0]
    real_walk = _base.walk_fields

    def counting(*args: Any) -> Any:
        walks[0] += 1
        return real_walk(*args)

    monkeypatch.setattr(_base, "walk_fields", counting)
    rng = random.Random(f"fast-validation-{cls.__name__}")
    kinds = [kind for _name, kind in cls.FIELDS]
    fast_hits = refused = 0
    for trial in range(600):
        odd_rate = 0.0 if trial % 4 == 0 else rng.random()
        values = [_odd(k, rng) if rng.random() < odd_rate else _good(k, rng) for k in kinds]
        if any(hasattr(v, "__next__") for v in values):  # an iterator is consumed once
            values_again = [tuple(v) if hasattr(v, "__next__") else v for v in values]
            values = [list(v) if isinstance(v, tuple) else v for v in values_again]
        walks_before = walks[0]
        fast = _outcome(cls._validated, cls, list(values))
        slow = _outcome(partial(validated_fields, cls), cls, list(values))
        assert fast == slow, (cls.__name__, values)
        refused += isinstance(fast, tuple) and fast[0] == "raised"
        fast_hits += walks[0] == walks_before
    assert fast_hits > 0  # the quick stage answered, not only the field-by-field one
    assert walks[0] > 0  # and the field-by-field stage was reached
    assert refused > 0  # and refusals were compared too


@pytest.mark.parametrize("value", FLOATS, ids=repr)
def test_every_float_edge_in_every_joint_slot(value: object) -> None:
    """Each edge value alone, in the scalar float and in each array slot of a point."""
    for slot in range(MAX_JOINTS + 1):
        pos: list[object] = [0.25] * MAX_JOINTS
        time: object = 0.5
        if slot == MAX_JOINTS:
            time = value
        else:
            pos[slot] = value
        values = [0, 1, 7, time, tuple(pos), (0.0,) * MAX_JOINTS, (0.0,) * MAX_JOINTS]
        fast = _outcome(JointTrajPtFull._validated, JointTrajPtFull, values)
        slow = _outcome(partial(validated_fields, JointTrajPtFull), JointTrajPtFull, values)
        assert fast == slow


def test_construction_still_words_the_refusal() -> None:
    with pytest.raises(LocalProtocolError, match=r"JointFeedback\.pos\[3\] = 1e\+39 does not fit"):
        JointFeedback.for_joints(0, [0.0, 0.0, 0.0, 1e39])
    with pytest.raises(LocalProtocolError, match=r"JointTrajPtFull\.sequence = 2147483648"):
        JointTrajPtFull.for_joints(0, 2**31, 0.0, [0.0], [0.0])


# --------------------------------------------------------------------------- decoding


def _random_frame(rng: random.Random, order: ByteOrder, port: Port) -> bytes:
    """A frame the controller could send on ``port``: right, wrong-size or unknown type."""
    table = REPLY_CLASSES[port]
    comm = rng.choice((CommType.TOPIC, CommType.SERVICE_REPLY, CommType.SERVICE_REQUEST, 9))
    reply = rng.choice((ReplyType.INVALID, ReplyType.SUCCESS, ReplyType.FAILURE))
    if table and rng.random() < 0.85:
        msg_type = rng.choice(sorted(table))
        size = table[msg_type].BODY_SIZE
        roll = rng.random()
        if roll < 0.1:
            size = max(0, size + rng.choice((-1, 1, -4, 4)))
        body = bytearray(rng.randbytes(size))
        # NaN, infinities and subnormals in float fields: decoding keeps them as they are.
        for at in range(0, size - 3, 4):
            if rng.random() < 0.05:
                body[at : at + 4] = struct.pack(
                    order + "f", rng.choice((math.nan, math.inf, -math.inf, 1.4e-45, F32_MAX))
                )
    else:
        msg_type = rng.choice((2, 99, 2000, 3000, 12345))
        body = bytearray(rng.randbytes(rng.randrange(0, 40)))
    return encode_frame(Frame(msg_type, int(comm), int(reply), bytes(body)), order)


def _decode_all(
    stream: bytes, chunks: list[int], order: ByteOrder, port: Port, fast: bool
) -> list[object]:
    decoder = FrameDecoder(order)
    out: list[object] = []
    at = 0
    for size in chunks:
        decoder.feed(stream[at : at + size])
        at += size
        while True:
            try:
                if fast:
                    message = decoder.next_reply(port)
                    if message is None:
                        break
                    out.append((message, decoder.comm_type))
                else:
                    frame = decoder.next_frame()
                    if frame is None:
                        break
                    out.append((decode_reply(frame, order, port), frame.comm_type))
            except RemoteProtocolError as exc:
                out.append(("error", str(exc), exc.data))
    return out


@pytest.mark.parametrize("order", list(ByteOrder), ids=lambda o: o.name)
@pytest.mark.parametrize("port", list(Port), ids=lambda p: p.name)
def test_next_reply_equals_next_frame_then_decode_reply(order: ByteOrder, port: Port) -> None:
    rng = random.Random(f"decode-{order.name}-{port.name}")
    for _ in range(40):
        stream = b"".join(_random_frame(rng, order, port) for _ in range(rng.randrange(1, 30)))
        chunks = []
        left = len(stream)
        while left > 0:
            chunks.append(min(left, rng.choice((1, 7, 16, 132, 148, 4096))))
            left -= chunks[-1]
        fast = _decode_all(stream, chunks, order, port, fast=True)
        slow = _decode_all(stream, chunks, order, port, fast=False)
        assert _decoded_key(fast) == _decoded_key(slow)


def _decoded_key(items: list[object]) -> list[object]:
    out: list[object] = []
    for item in items:
        assert isinstance(item, tuple)
        if item[0] == "error":
            out.append(item)
        else:
            message, comm = item
            out.append((type(message), repr(message), comm))  # repr: NaN compares as text
    return out


def test_comm_type_is_that_of_the_last_frame() -> None:
    decoder = FrameDecoder(ByteOrder.LITTLE)
    assert decoder.comm_type == 0
    decoder.feed(encode_frame(Frame(1, 3, 1, b""), ByteOrder.LITTLE))
    decoder.feed(encode_frame(Frame(13, 1, 0, bytes(28)), ByteOrder.LITTLE))
    assert decoder.next_reply(Port.MOTION) is not None  # PING's reply
    assert decoder.comm_type == 3
    decoder.next_reply(Port.STATE)
    assert decoder.comm_type == 1


# --------------------------------------------------------------------------- encoding

_DEFAULTS = {
    Role.REQUEST: (CommType.SERVICE_REQUEST, ReplyType.INVALID),
    Role.REPLY: (CommType.SERVICE_REPLY, ReplyType.SUCCESS),
    Role.TOPIC: (CommType.TOPIC, ReplyType.INVALID),
}


def _encode_reference(message: Message | UnknownMessage, order: ByteOrder) -> bytes:
    """The frame as ``encode`` derived it from the message before its per-class cache."""
    body = message.pack(order)
    comm, reply = _DEFAULTS[message.ROLE]
    if message.IO_RESULT and getattr(message, "result_code", 0) != 0:
        reply = ReplyType.FAILURE
    msg_type = message.msg_type if isinstance(message, UnknownMessage) else message.MSG_TYPE
    return struct.pack(order + "iiii", HEADER_SIZE + len(body), msg_type, comm, reply) + body


def _sample(cls: type[Message], rng: random.Random) -> Message:
    values = []
    for _name, kind in cls.FIELDS:
        if kind is U32:
            values.append(rng.choice((0, 0, 1, 5, 2**32 - 1)))
        elif kind is I32:
            values.append(rng.choice((0, 0, 1, -3, 2**31 - 1)))
        else:
            values.append(_good(kind, rng))
    return cls(*values)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_encode_equals_the_header_from_the_message(cls: type[Message]) -> None:
    rng = random.Random(f"encode-{cls.__name__}")
    for order in ByteOrder:
        for _ in range(20):
            message = _sample(cls, rng)
            assert encode(message, order) == _encode_reference(message, order)
            assert encode(message, order, comm_type=7, reply_type=9)[8:16] == struct.pack(
                order + "ii", 7, 9
            )


def test_encode_unknown_messages_keep_their_own_type() -> None:
    for msg_type in (2, 77, -5):
        message = UnknownMessage(msg_type, b"\x01\x02")
        for order in ByteOrder:
            assert encode(message, order) == _encode_reference(message, order)


def test_encode_errors_unchanged() -> None:
    with pytest.raises(ProtocolError, match="exceed"):
        encode(UnknownMessage(2, bytes(600)), ByteOrder.LITTLE)


# --------------------------------------------------------------------------- packing


def _pack_reference(message: Message, order: ByteOrder) -> bytes:
    """``Message.pack`` with the field-by-field flattening it had before ``_LEADING``."""
    layout = struct.Struct(order + "".join(kind.value for _name, kind in message.FIELDS))
    try:
        flat: list[object] = []
        for (_name, kind), value in zip(message.FIELDS, message, strict=True):
            if kind is JOINTS:
                flat.extend(value)
            else:
                flat.append(value)
        return layout.pack(*flat)
    except (struct.error, OverflowError, TypeError) as exc:
        raise LocalProtocolError(f"cannot pack {message!r}: {exc}") from None


ARRAYS_LAST = [
    cls for cls in CLASSES if cls._LEADING >= 0 and not cls._FLAT and "pack" not in cls.__dict__
]


@pytest.mark.parametrize("cls", ARRAYS_LAST, ids=lambda c: c.__name__)
def test_pack_of_arrays_last_layouts_equals_the_field_by_field_flattening(
    cls: type[Message],
) -> None:
    rng = random.Random(f"pack-{cls.__name__}")
    names = [name for name, _kind in cls.FIELDS]
    odd: list[object] = [(0.0,) * 9, (0.0,) * 11, 5, None, ("x",) * 10, (1e39,) * 10, 2**40]
    for _ in range(300):
        message = _sample(cls, rng)
        if rng.random() < 0.5:  # _replace skips validation: pack is where it fails
            message = message._replace(**{rng.choice(names): rng.choice(odd)})  # type: ignore[attr-defined]
        for order in ByteOrder:
            outcomes = []
            for pack in (lambda m, o: m.pack(o), _pack_reference):
                try:
                    outcomes.append(pack(message, order))
                except Exception as exc:  # type and text compared
                    outcomes.append((type(exc), str(exc)))
            assert outcomes[0] == outcomes[1]
    assert ARRAYS_LAST  # MOTO_MOTION_CTRL and MOTO_MOTION_REPLY at least


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_positional_construction_equals_the_namedtuple_path(cls: type[Message]) -> None:
    """All fields by position skip the NamedTuple's ``__new__``; by keyword they do not."""
    rng = random.Random(f"construct-{cls.__name__}")
    kinds = [kind for _name, kind in cls.FIELDS]
    names = list(cls._fields)  # type: ignore[attr-defined]
    for _ in range(200):
        values = [_odd(k, rng) if rng.random() < 0.2 else _good(k, rng) for k in kinds]
        values = [tuple(v) if hasattr(v, "__next__") else v for v in values]
        outcomes = []
        by_name = dict(zip(names, values, strict=True))
        for args, kwargs in ((values, {}), ([], by_name)):
            try:
                made = cls(*args, **kwargs)
                outcomes.append(("ok", type(made), _key(tuple(made))))
            except Exception as exc:  # type and text compared
                outcomes.append(("raised", type(exc), str(exc)))
        assert outcomes[0] == outcomes[1]
    with pytest.raises(TypeError):  # one field too many: still the NamedTuple's own error
        cls(*[_good(k, rng) for k in kinds], 0)


def _reply_echo_reference(message: Message) -> tuple[int, int] | None:
    """``reply_echo`` as it read ``ROLE`` and ``OFFSETS`` per call."""
    offsets = message.OFFSETS
    if message.ROLE is not Role.REQUEST or "sequence" not in offsets:
        return None
    fields: Any = message
    command = fields.command if "command" in offsets else message.MSG_TYPE
    return int(command), int(fields.sequence)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_reply_echo_decided_per_class_equals_per_message(cls: type[Message]) -> None:
    rng = random.Random(f"echo-{cls.__name__}")
    for _ in range(20):
        message = _sample(cls, rng)
        assert message.reply_echo() == _reply_echo_reference(message)


def test_reply_echo_of_the_hand_laid_out_messages() -> None:
    from pymotoros.protocol.messages import MotoJointFeedbackEx, MotoJointTrajPtFullEx

    record = JointTrajPtExData.for_joints(1, 0.5, [0.1], [0.0])
    full_ex = MotoJointTrajPtFullEx.for_groups(42, [record])
    feedback_ex = MotoJointFeedbackEx.for_groups([JointFeedback.for_joints(0, [0.1])])
    for message in (full_ex, feedback_ex):
        assert message.reply_echo() == _reply_echo_reference(message)
    assert full_ex.reply_echo() == (2016, 42)
