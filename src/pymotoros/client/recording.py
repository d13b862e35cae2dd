"""Reading a session recording back: connections, chunks and Simple Message messages.

:func:`read_recording` opens a pcapng file written by the session recorder
(:mod:`pymotoros.client.recorder`, ``--record``, ``pymotoros sim --record``) and
gives back what travelled: every TCP connection (server and client port, which
MotoROS port it was, byte order), every chunk of payload in order with its time
and direction, and each direction's byte stream reassembled into decoded Simple
Message messages, each stamped with the time of the chunk that completed it.
``replay`` and ``plot --recording`` are built on it.

It also reads a capture Wireshark or tcpdump made of a real session (Ethernet,
loopback, Linux cooked or raw IP link types; IPv4 only), as long as it holds the
whole TCP stream: a gap in the sequence numbers is an error, not a guess.

Which MotoROS port a connection is: the standard port numbers (50240, 50241,
50242) say it; for other server ports (a twin on port 0) the traffic does: the
server pushing topics is the state port, a client sending motion-only types the
motion port, and IO-only types the IO port. Pass ``ports`` to say it yourself.
The byte order is read from the first length prefix of each connection (MotoROS
never swaps bytes: big-endian on the FS100, little-endian on the others).

Why a reader on top of dpkt rather than tshark: it needs no external program, and
decoding uses the same codec as the client and the twin, so what it reports is
exactly what they saw.
"""

from __future__ import annotations

import enum
import socket
import struct
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final, TypeAlias

import dpkt
import dpkt.pcapng

from pymotoros.errors import PymotorosError, RemoteProtocolError
from pymotoros.protocol.constants import PREFIX_SIZE, STANDARD_PORTS, ByteOrder, CommType, Port
from pymotoros.protocol.framing import (
    REQUEST_CLASSES,
    Frame,
    FrameDecoder,
    decode_reply,
    decode_request,
    prefix_fits,
)
from pymotoros.protocol.messages import WireMessage

__all__ = [
    "Direction",
    "RecordedChunk",
    "RecordedConnection",
    "RecordedMessage",
    "Recording",
    "RecordingError",
    "read_recording",
]

_SEQ_MOD: Final = 1 << 32
"""TCP sequence numbers wrap at 2**32."""

_MOTION_ONLY: Final = frozenset(REQUEST_CLASSES[Port.MOTION]) - frozenset(REQUEST_CLASSES[Port.IO])
_IO_ONLY: Final = frozenset(REQUEST_CLASSES[Port.IO]) - frozenset(REQUEST_CLASSES[Port.MOTION])
"""Request types only one port accepts: what tells a motion from an IO connection."""

_Framed: TypeAlias = tuple[int, float, Frame]
"""(position in the file of the chunk that completed the frame, its time, the frame)."""


class RecordingError(PymotorosError, ValueError):
    """The file is not a readable recording of a Simple Message session; says why.

    Also a ``ValueError``: ``pymotoros replay`` and ``check --recording`` catch it as one."""


class Direction(enum.StrEnum):
    """Which way a chunk or message travelled."""

    TO_SERVER = "to_server"
    """Client → controller (requests)."""
    FROM_SERVER = "from_server"
    """Controller → client (replies and state topics)."""


@dataclass(frozen=True, slots=True)
class RecordedChunk:
    """One TCP segment with payload, as written or read by one side."""

    time: float
    """Absolute time (s since the epoch) the recorder stamped on it."""
    offset: float
    """Seconds since the first packet of the recording."""
    connection: int
    """Index of its connection in :attr:`Recording.connections`."""
    server_port: int
    client_port: int
    direction: Direction
    payload: bytes


@dataclass(frozen=True, slots=True)
class RecordedMessage:
    """One whole Simple Message frame of a direction's stream, decoded.

    ``time``/``offset`` are those of the chunk that completed the frame.
    ``message`` is None when the frame could not be decoded (a body of the wrong
    size for its type, or a connection whose port is unknown); ``problem`` then
    says why. Types the port does not know decode as ``UnknownMessage``.
    """

    time: float
    offset: float
    connection: int
    server_port: int
    client_port: int
    kind: Port | None
    direction: Direction
    frame: Frame
    message: WireMessage | None
    problem: str | None = None

    @property
    def msg_type(self) -> int:
        return self.frame.msg_type

    @property
    def is_topic(self) -> bool:
        """A state topic pushed by the controller (not a reply to a request)."""
        return self.frame.comm_type == CommType.TOPIC


@dataclass(frozen=True, slots=True)
class RecordedConnection:
    """One TCP connection: its ports, which MotoROS port it is, and its traffic."""

    index: int
    server_port: int
    client_port: int
    kind: Port | None
    """Motion, state or IO port; None if neither the port number nor the traffic says."""
    order: ByteOrder | None
    """Byte order of its frames; None when no payload travelled."""
    opened: float
    """Offset (s) of its first packet (the SYN, when recorded)."""
    closed: float | None
    """Offset (s) of its first FIN or RST, None if the recording ends with it open."""
    chunks: tuple[RecordedChunk, ...]
    messages: tuple[RecordedMessage, ...]
    trailing: Mapping[Direction, int] = field(default_factory=dict)
    """Bytes at the end of each direction that do not make a whole frame (a cut recording)."""
    client: str = ""
    """The client's end, "host:port" (as the twin names a connection)."""

    def sent(self) -> tuple[RecordedMessage, ...]:
        """Messages the client sent."""
        return tuple(m for m in self.messages if m.direction is Direction.TO_SERVER)

    def received(self) -> tuple[RecordedMessage, ...]:
        """Messages the controller sent (replies and topics)."""
        return tuple(m for m in self.messages if m.direction is Direction.FROM_SERVER)


@dataclass(frozen=True, slots=True)
class Recording:
    """A whole recording: its connections, and all chunks and messages in time order."""

    path: Path
    start: float
    """Absolute time (s since the epoch) of the first packet; offsets count from it."""
    end: float
    """Absolute time of the last packet."""
    connections: tuple[RecordedConnection, ...]
    chunks: tuple[RecordedChunk, ...]
    messages: tuple[RecordedMessage, ...]

    @property
    def duration(self) -> float:
        return self.end - self.start

    @property
    def order(self) -> ByteOrder | None:
        """The byte order of the session (every connection shares it), None if no payload."""
        orders = {c.order for c in self.connections if c.order is not None}
        return next(iter(orders)) if len(orders) == 1 else None

    def on(self, kind: Port) -> tuple[RecordedConnection, ...]:
        """The connections to one MotoROS port, in the order they opened."""
        return tuple(c for c in self.connections if c.kind is kind)


# --------------------------------------------------------------------------- packets


@dataclass(slots=True)
class _Segment:
    ts: float
    src: tuple[bytes, int]
    dst: tuple[bytes, int]
    seq: int
    flags: int
    payload: bytes


def _ip_of(link: int, frame: bytes) -> dpkt.ip.IP | None:
    """The IPv4 packet inside a link-layer frame, None for anything else (ARP, IPv6 …)."""
    try:
        if link == dpkt.pcap.DLT_EN10MB:
            pkt: object = dpkt.ethernet.Ethernet(frame).data
        elif link in (dpkt.pcap.DLT_NULL, dpkt.pcap.DLT_LOOP):
            pkt = dpkt.loopback.Loopback(frame).data
        elif link == dpkt.pcap.DLT_LINUX_SLL:
            pkt = dpkt.sll.SLL(frame).data
        elif link in (dpkt.pcap.DLT_RAW, _DLT_IPV4):
            pkt = dpkt.ip.IP(frame)
        else:
            raise RecordingError(
                f"link type {link} is not supported: record with pymotoros --record, or "
                "capture on an Ethernet or loopback interface"
            )
    except (dpkt.UnpackError, struct.error):
        return None
    return pkt if isinstance(pkt, dpkt.ip.IP) else None


_DLT_IPV4: Final = 228
"""LINKTYPE_IPV4 (tcpdump.org link-layer header types): raw IPv4, no link header."""


def _segments(path: Path) -> tuple[list[_Segment], int]:
    """Every TCP segment of the file, and how many packets it holds in all."""
    try:
        handle = path.open("rb")
    except OSError as exc:
        raise RecordingError(f"cannot open {path}: {exc.strerror or exc}") from None
    with handle:
        try:
            reader = dpkt.pcapng.Reader(handle)
        except (ValueError, dpkt.UnpackError, struct.error) as exc:
            raise RecordingError(
                f"{path} is not a pcapng file ({exc}); record one with --record FILE "
                "(pcap files from tcpdump: convert with `editcap -F pcapng`)"
            ) from None
        link = reader.datalink()
        segments: list[_Segment] = []
        packets = 0
        try:
            for ts, frame in reader:
                packets += 1
                ip = _ip_of(link, frame)
                if ip is None or not isinstance(ip.data, dpkt.tcp.TCP):
                    continue
                tcp = ip.data
                segments.append(
                    _Segment(
                        float(ts),
                        (bytes(ip.src), int(tcp.sport)),
                        (bytes(ip.dst), int(tcp.dport)),
                        int(tcp.seq),
                        int(tcp.flags),
                        bytes(tcp.data),
                    )
                )
        except (ValueError, dpkt.UnpackError, struct.error) as exc:
            raise RecordingError(
                f"{path}: damaged pcapng block after {packets} packets ({exc})"
            ) from None
    return segments, packets


# --------------------------------------------------------------------------- connections


@dataclass(slots=True)
class _Conn:
    client: tuple[bytes, int]
    server: tuple[bytes, int]
    opened: float
    closed: float | None = None
    next_seq: dict[Direction, int | None] = field(
        default_factory=lambda: {Direction.TO_SERVER: None, Direction.FROM_SERVER: None}
    )
    chunks: list[tuple[int, float, Direction, bytes]] = field(default_factory=list)
    """(position in the file, time, direction, payload)."""


def _endpoint(addr: tuple[bytes, int]) -> str:
    return f"{socket.inet_ntoa(addr[0])}:{addr[1]}"


def _server_side(seg: _Segment, known: Mapping[int, Port]) -> tuple[bytes, int] | None:
    """Which end of a connection whose handshake was not recorded is the controller."""
    if seg.dst[1] in known and seg.src[1] not in known:
        return seg.dst
    if seg.src[1] in known and seg.dst[1] not in known:
        return seg.src
    return None


def _connections(
    path: Path, segments: Iterable[_Segment], known: Mapping[int, Port]
) -> list[_Conn]:
    """Group segments into connections (a SYN starts one) and check each stream is whole."""
    conns: list[_Conn] = []
    live: dict[frozenset[tuple[bytes, int]], _Conn] = {}
    syn, ack = dpkt.tcp.TH_SYN, dpkt.tcp.TH_ACK
    for position, seg in enumerate(segments):
        key = frozenset((seg.src, seg.dst))
        conn = live.get(key)
        if seg.flags & syn and not seg.flags & ack:
            conn = _Conn(client=seg.src, server=seg.dst, opened=seg.ts)
            conn.next_seq[Direction.TO_SERVER] = (seg.seq + 1) % _SEQ_MOD
            live[key] = conn
            conns.append(conn)
            continue
        if conn is None:
            server = _server_side(seg, known)
            if server is None:
                raise RecordingError(
                    f"{path}: a TCP connection {_endpoint(seg.src)} ↔ {_endpoint(seg.dst)} "
                    "started before the recording and neither port is a MotoROS port: "
                    "cannot tell the controller's side (pass ports=… to read_recording)"
                )
            client = seg.dst if server == seg.src else seg.src
            conn = _Conn(client=client, server=server, opened=seg.ts)
            live[key] = conn
            conns.append(conn)
        direction = Direction.TO_SERVER if seg.src == conn.client else Direction.FROM_SERVER
        if seg.flags & syn:  # SYN+ACK: the server's initial sequence number
            conn.next_seq[direction] = (seg.seq + 1) % _SEQ_MOD
            continue
        if seg.payload:
            expected = conn.next_seq[direction]
            if expected is not None and seg.seq != expected:
                behind = (expected - seg.seq) % _SEQ_MOD
                if behind < _SEQ_MOD // 2 and behind >= len(seg.payload):
                    continue  # a retransmission of bytes already taken
                raise RecordingError(
                    f"{path}: the {direction.value.replace('_', ' ')} stream of "
                    f"{_endpoint(conn.client)} → {_endpoint(conn.server)} is not whole at "
                    f"t={seg.ts - conns[0].opened:.6f} s (sequence {seg.seq}, expected "
                    f"{expected}): the capture lost or reordered packets"
                )
            conn.next_seq[direction] = (seg.seq + len(seg.payload)) % _SEQ_MOD
            conn.chunks.append((position, seg.ts, direction, seg.payload))
        if seg.flags & (dpkt.tcp.TH_FIN | dpkt.tcp.TH_RST) and conn.closed is None:
            conn.closed = seg.ts
    return conns


# --------------------------------------------------------------------------- decoding


def _byte_order(data: bytes) -> ByteOrder | None:
    """The byte order in which ``data`` starts with a legal length prefix, if one does."""
    return next((o for o in (ByteOrder.LITTLE, ByteOrder.BIG) if prefix_fits(data, o)), None)


def _frames(
    path: Path, what: str, chunks: list[tuple[int, float, bytes]], order: ByteOrder
) -> tuple[list[_Framed], int]:
    """Reassemble one direction into frames stamped with their completing chunk; and the
    bytes left over."""
    decoder = FrameDecoder(order)
    out: list[_Framed] = []
    for position, ts, data in chunks:
        decoder.feed(data)
        try:
            out.extend((position, ts, frame) for frame in decoder.frames())
        except RemoteProtocolError as exc:
            raise RecordingError(
                f"{path}: {what} is not Simple Message ({exc}) after {len(out)} frames; "
                "this is not a recording of a MotoROS session"
            ) from None
    return out, decoder.buffered


def _kind_from_traffic(client_frames: list[_Framed], server_frames: list[_Framed]) -> Port | None:
    if any(f.comm_type == CommType.TOPIC for _, _, f in server_frames):
        return Port.STATE
    types = {f.msg_type for _, _, f in client_frames}
    if types & _MOTION_ONLY:
        return Port.MOTION
    if types:
        return Port.IO if types <= frozenset(REQUEST_CLASSES[Port.IO]) else Port.MOTION
    return None


def _decode(
    frame: Frame, order: ByteOrder | None, kind: Port | None, direction: Direction
) -> tuple[WireMessage | None, str | None]:
    if order is None:  # pragma: no cover - frames exist only when the order was found
        return None, "the byte order was not found"
    if kind is None:
        return None, "which MotoROS port the connection is was not found"
    try:
        if direction is Direction.TO_SERVER:
            return decode_request(frame, order, kind), None
        return decode_reply(frame, order, kind), None
    except RemoteProtocolError as exc:
        return None, str(exc)


def read_recording(
    path: str | Path,
    *,
    ports: Mapping[int, Port] | None = None,
) -> Recording:
    """Read a pcapng session recording; :class:`RecordingError` says what is wrong with it.

    ``ports`` maps server port numbers to the MotoROS port they are (in addition
    to the standard 50240/50241/50242), for recordings whose kind the traffic
    does not reveal (a connection to a non-standard port that carried nothing).
    """
    path = Path(path)
    known: dict[int, Port] = {**STANDARD_PORTS, **(ports or {})}
    segments, packets = _segments(path)
    if not segments:
        raise RecordingError(
            f"{path} holds {packets} packets and no TCP: not a recording of a MotoROS session"
        )
    raw = _connections(path, segments, known)
    start = min(seg.ts for seg in segments)
    end = max(seg.ts for seg in segments)
    connections: list[RecordedConnection] = []
    ordered_messages: list[tuple[int, RecordedMessage]] = []
    ordered_chunks: list[tuple[int, RecordedChunk]] = []
    for index, conn in enumerate(raw):
        server_port, client_port = conn.server[1], conn.client[1]
        label = f"connection {index} ({_endpoint(conn.client)} → {_endpoint(conn.server)})"
        order: ByteOrder | None = None
        for _, _, _, data in conn.chunks:
            order = _byte_order(data)
            if order is None:
                raise RecordingError(
                    f"{path}: {label} does not start with a Simple Message length prefix "
                    f"(first bytes {data[:PREFIX_SIZE].hex()}): not a MotoROS session"
                )
            break
        chunks = tuple(
            RecordedChunk(ts, ts - start, index, server_port, client_port, direction, data)
            for _, ts, direction, data in conn.chunks
        )
        ordered_chunks.extend((p, c) for (p, *_), c in zip(conn.chunks, chunks, strict=True))
        framed: dict[Direction, list[_Framed]] = {d: [] for d in Direction}
        trailing: dict[Direction, int] = {}
        if order is not None:
            for direction in Direction:
                mine = [(p, ts, data) for p, ts, d, data in conn.chunks if d is direction]
                what = f"the {direction.value.replace('_', ' ')} stream of {label}"
                framed[direction], left = _frames(path, what, mine, order)
                if left:
                    trailing[direction] = left
        kind = known.get(server_port) or _kind_from_traffic(
            framed[Direction.TO_SERVER], framed[Direction.FROM_SERVER]
        )
        messages: list[tuple[int, RecordedMessage]] = []
        for direction in Direction:
            for position, ts, frame in framed[direction]:
                message, problem = _decode(frame, order, kind, direction)
                messages.append(
                    (
                        position,
                        RecordedMessage(
                            ts,
                            ts - start,
                            index,
                            server_port,
                            client_port,
                            kind,
                            direction,
                            frame,
                            message,
                            problem,
                        ),
                    )
                )
        messages.sort(key=lambda pm: pm[0])  # stable: a chunk's frames keep their order
        ordered_messages.extend(messages)
        connections.append(
            RecordedConnection(
                index=index,
                server_port=server_port,
                client_port=client_port,
                kind=kind,
                order=order,
                opened=conn.opened - start,
                closed=None if conn.closed is None else conn.closed - start,
                chunks=chunks,
                messages=tuple(m for _, m in messages),
                trailing=trailing,
                client=_endpoint(conn.client),
            )
        )
    # file order (the order the recorder wrote them), not a sort by time that could
    # swap a request and its reply stamped in the same microsecond
    ordered_chunks.sort(key=lambda pc: pc[0])
    all_chunks = [c for _, c in ordered_chunks]
    ordered_messages.sort(key=lambda pm: pm[0])
    all_messages = [m for _, m in ordered_messages]
    return Recording(
        path=path,
        start=start,
        end=end,
        connections=tuple(connections),
        chunks=tuple(all_chunks),
        messages=tuple(all_messages),
    )
