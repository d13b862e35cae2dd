"""The codec fuzzed with Hypothesis (issue 13, item 7): what the servers and the client
actually call, on any bytes in any chunking.

- Any byte string, cut anywhere, fed to a :class:`FrameDecoder` and read with every
  ``next_*`` method (the fused paths the servers and the client use) and
  :func:`sizes.check_request` (what the motion and IO servers answer with) either yields
  values or raises :class:`RemoteProtocolError`, never another exception; the buffer
  never holds more than one frame's worth; after an error, :meth:`discard` resynchronises.
- A stream of generated valid messages of every type, both byte orders, cut anywhere,
  decodes to exactly the messages sent (NaN payloads bit for bit).

Each property is bounded by ``max_examples`` (CI);
``PYMOTOROS_FUZZ_SCALE=20 python -m pytest tests/protocol/test_fuzz_codec.py`` runs
twenty times as many.
"""

from __future__ import annotations

import itertools
import math
import os
import struct
from collections.abc import Callable

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_message_roundtrip import MESSAGES

from pymotoros.errors import RemoteProtocolError
from pymotoros.protocol import ByteOrder, FrameDecoder, Message, Port, encode
from pymotoros.protocol.constants import MAX_WIRE_MESSAGE_SIZE
from pymotoros.protocol.messages import JointTrajPtFull, UnknownMessage
from pymotoros.protocol.sizes import Accept, Close, Reject, check_request

SCALE = int(os.environ.get("PYMOTOROS_FUZZ_SCALE", "1"))
"""Multiplier of every property's examples: 1 in CI (seconds), more on demand."""

ORDERS = [ByteOrder.LITTLE, ByteOrder.BIG]


def examples(n: int) -> Callable[[Callable[..., None]], Callable[..., None]]:
    """Bounded examples; no time limits (this shared 2-core machine and CI runners are
    slow at times, which says nothing about the codec)."""
    return settings(
        max_examples=n * SCALE, deadline=None, suppress_health_check=[HealthCheck.too_slow]
    )


def cut(data: bytes, cuts: list[int]) -> list[bytes]:
    points = sorted({0, len(data), *(c % (len(data) + 1) for c in cuts)})
    return [data[a:b] for a, b in itertools.pairwise(points)]


def valid_header_frames() -> st.SearchStrategy[bytes]:
    """Frames with a legal length prefix and anything after it: they get past the
    framing, so the typed decoders see arbitrary types and bodies of arbitrary size."""
    return st.builds(
        lambda msg_type, comm, reply, body: struct.pack(
            "<iiii", 12 + len(body), msg_type, comm, reply
        )
        + body,
        st.sampled_from([1, 2, 13, 14, 15, 2001, 2002, 2003, 2004, 2016, 2017, 2018, 2020,
                         2003, 2010, 2011, 2012, 2013, -1, 0, 99999]),
        st.integers(-2, 4),
        st.integers(-2, 4),
        st.binary(max_size=MAX_WIRE_MESSAGE_SIZE - 16),
    )  # fmt: skip


STREAMS = st.lists(st.one_of(st.binary(max_size=64), valid_header_frames()), max_size=8).map(
    b"".join
)
"""Noise and plausible frames, mixed: a stream a buggy or hostile peer might send."""

NEXT: dict[str, Callable[[FrameDecoder], object]] = {
    "frame": FrameDecoder.next_frame,
    **{f"reply-{p.name}": (lambda d, p=p: d.next_reply(p)) for p in Port},
    **{f"request-{p.name}": (lambda d, p=p: d.next_request(p)) for p in Port},
}


def any_chunked_stream(test: Callable[..., None]) -> Callable[..., None]:
    """``test`` in both byte orders, on 150 STREAMS each cut into chunks anywhere."""
    test = examples(150)(test)
    test = given(data=STREAMS, cuts=st.lists(st.integers(0, 10_000), max_size=8))(test)
    return pytest.mark.parametrize("order", ORDERS, ids=["le", "be"])(test)


def run_stream(decoder: FrameDecoder, chunks: list[bytes], read: Callable[..., object]) -> int:
    """Feed every chunk, read until None; on RemoteProtocolError discard and go on."""
    values = 0
    for chunk in chunks:
        decoder.feed(chunk)
        while True:
            try:
                value = read(decoder)
            except RemoteProtocolError:
                decoder.discard()
                continue
            if value is None:
                break
            values += 1
        assert decoder.buffered < MAX_WIRE_MESSAGE_SIZE, decoder.buffered
    return values


@pytest.mark.parametrize("path", sorted(NEXT))
@any_chunked_stream
def test_any_bytes_any_chunking_yield_values_or_the_typed_error(
    path: str, order: ByteOrder, data: bytes, cuts: list[int]
) -> None:
    run_stream(FrameDecoder(order), cut(data, cuts), NEXT[path])


@pytest.mark.parametrize("port", [Port.MOTION, Port.IO])
@any_chunked_stream
def test_the_servers_size_rules_on_any_frame(
    port: Port, order: ByteOrder, data: bytes, cuts: list[int]
) -> None:
    """What the motion and IO servers do with each frame: a verdict, or the typed error."""

    def judge(decoder: FrameDecoder) -> object:
        frame = decoder.next_frame()
        if frame is None:
            return None
        verdict = check_request(frame, order, port)
        assert isinstance(verdict, Accept | Reject | Close)
        return verdict

    run_stream(FrameDecoder(order), cut(data, cuts), judge)


def same(a: object, b: object) -> bool:
    """Equal, with NaN equal to a NaN of the same bits (encode keeps the payload)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a):
        return struct.pack("<d", a) == struct.pack("<d", b)
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


MESSAGE_SETS: dict[Port, list[tuple[st.SearchStrategy[Message], bool]]] = {}
for _strategy, _port, _request in MESSAGES.values():
    MESSAGE_SETS.setdefault(_port, []).append((_strategy, _request))


SIDES = [
    pytest.param(port, side, id=f"{port.name}-{'requests' if side else 'replies'}")
    for port in Port
    for side in (True, False)
    if any(request is side for _, request in MESSAGE_SETS.get(port, []))
]
"""Every (port, direction) that has message types: the state port has no requests."""


@pytest.mark.parametrize(("port", "request_side"), SIDES)
@pytest.mark.parametrize("order", ORDERS, ids=["le", "be"])
@given(data=st.data(), cuts=st.lists(st.integers(0, 100_000), max_size=12))
@examples(40)
def test_a_stream_of_valid_messages_of_every_type_round_trips(
    order: ByteOrder, port: Port, request_side: bool, data: st.DataObject, cuts: list[int]
) -> None:
    kinds = [s for s, request in MESSAGE_SETS[port] if request is request_side]
    messages = data.draw(st.lists(st.one_of(kinds), min_size=1, max_size=10))
    decoder = FrameDecoder(order)
    got: list[object] = []
    for chunk in cut(b"".join(encode(m, order) for m in messages), cuts):
        decoder.feed(chunk)
        read = decoder.next_request if request_side else decoder.next_reply
        while (message := read(port)) is not None:
            assert not isinstance(message, UnknownMessage), message
            got.append(message)
    assert decoder.buffered == 0
    assert len(got) == len(messages)
    for sent, received in zip(messages, got, strict=True):
        assert type(sent) is type(received)
        assert same(tuple(sent), tuple(received)), (sent, received)


@given(
    st.lists(st.floats(width=32), min_size=6, max_size=6),
    st.floats(width=32),
    st.sampled_from(ORDERS),
)
@examples(100)
def test_any_float32_including_nan_and_infinities_round_trips(
    positions: list[float], time: float, order: ByteOrder
) -> None:
    point = JointTrajPtFull.for_joints(0, 1, time, positions, [0.0] * 6)
    decoder = FrameDecoder(order)
    decoder.feed(encode(point, order))
    back = decoder.next_request(Port.MOTION)
    assert isinstance(back, JointTrajPtFull)
    assert same(tuple(back), tuple(point))
