"""MotoROS 1.9.12's receive loop as a sans-I/O object: the server side of fidelity exact.

MotoROS reads its motion (and IO) port with one ``recv`` of at most 552 bytes (the
size of its message struct, §1.1) into a buffer, and decides from that buffer alone,
never reading the length prefix (§1.5):

- fewer than 16 bytes: INVALID/3001;
- an unknown type: INVALID/3003, the rest of the buffer dropped;
- fewer bytes than the type needs: INVALID/3001, the bytes dropped (no reassembly: a
  message split across two reads gets 3001 and its tail is read as a new message,
  usually 3003);
- otherwise the message is processed; bytes beyond its type's size are kept. When
  they hold a whole message (or at least a header of an unknown type) it is
  processed next without reading; otherwise MotoROS reads the next ``recv`` to a
  wrong address (its pointer arithmetic counts whole structs, §1.5): undefined
  behaviour, which the twin replaces by what the code means to do: the kept bytes are
  joined with the next read (at most 552 bytes together).
- A FULL_EX of exactly 552 bytes whose ``numberOfValidGroups`` is below 4: the padding
  is ignored.

**One read** of the twin is one read of the server's stream (``StreamReader.read``),
which returns whatever the client's bytes have delivered so far, up to the size asked:
the same as ``recv`` on the robot. A client that writes each message in one ``send``
and waits for its reply is never split; one that writes a message in two ``send``
calls may be, on the robot as on the twin, when the first piece is read before the
second arrives. Several messages written back to back may come in one read: they are
taken one after another as long as each read ends on a message boundary.

:class:`MotoRosReceiver` keeps that loop's state for one connection; the servers feed
it their reads and take one :class:`Turn` (one pass of the loop, one reply) at a time.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Final

from pymotoros.protocol.constants import (
    MAX_MESSAGE_SIZE,
    ByteOrder,
    InvalidSubcode,
    MsgType,
    Port,
)
from pymotoros.protocol.framing import FRAME_OVERHEAD, Frame
from pymotoros.protocol.sizes import (
    Reject,
    Verdict,
    check_request,
    expected_size,
    short_message_reply,
)

__all__ = ["RECV_SIZE", "MotoRosReceiver", "Turn", "turn_verdict"]

RECV_SIZE: Final = MAX_MESSAGE_SIZE
"""Bytes one ``recv`` of MotoROS asks for: its message struct, 552 (§1.1)."""

_HEAD: Final = {o: struct.Struct(o + "iiii") for o in ("<", ">")}


@dataclass(frozen=True, slots=True)
class Turn:
    """One pass of MotoROS's receive loop: the message it looks at, and why."""

    frame: Frame
    """Header (zero-filled where fewer than 16 bytes arrived) and the body bytes MotoROS
    looks at: up to the type's size, all that arrived when fewer."""
    received: int
    """Bytes in the buffer this pass (what ``recv`` returned, with kept bytes)."""
    expected: int | None
    """Total bytes the type needs (None: fewer than 16 bytes, or an unknown type)."""
    prefix: int | None
    """The length prefix as sent (never read by MotoROS); None when it did not arrive."""
    cut: bool
    """The read ended before the message did (fewer than 16 bytes, or fewer than the
    type needs): a message split across reads, answered 3001."""
    joined: bool
    """The bytes came partly from the previous read (its surplus) and partly from this
    one: the out-of-bounds case of §1.5, joined as the code means to."""

    @property
    def length_mismatch(self) -> bool:
        """A whole message whose prefix disagrees with its type's size (the robot does
        not care; a framing client or proxy would)."""
        return (
            not self.cut
            and self.expected is not None
            and self.prefix is not None
            and self.prefix + 4 != self.expected
        )


class MotoRosReceiver:
    """The receive buffer of one MotoROS connection (motion or IO port), sans I/O.

    ``wants_read`` says whether the loop reads before its next pass, ``read_size`` how
    many bytes it asks for; ``feed`` hands it one read, ``turn`` runs one pass.
    """

    __slots__ = ("_buf", "_joined", "_order", "_port", "_ready")

    def __init__(self, order: ByteOrder, port: Port) -> None:
        self._order = order
        self._port = port
        self._buf = b""
        self._ready = False
        self._joined = False

    @property
    def wants_read(self) -> bool:
        """No whole message is waiting: the next pass reads first."""
        return not self._ready

    @property
    def read_size(self) -> int:
        """What the next ``recv`` asks for: the struct less the bytes kept."""
        return RECV_SIZE - len(self._buf)

    def feed(self, data: bytes) -> None:
        """One read's bytes (after kept surplus bytes, if any)."""
        if self._ready:
            raise RuntimeError("a whole message is waiting: take its turn before reading")
        if len(data) > self.read_size:
            raise ValueError(f"a read returns at most {self.read_size} bytes, got {len(data)}")
        self._joined = bool(self._buf)
        self._buf += data
        self._ready = True

    def turn(self) -> Turn:
        """One pass of the loop over the buffer; keeps what belongs to the next pass."""
        if not self._ready:
            raise RuntimeError("nothing to process: feed a read first")
        buf, joined = self._buf, self._joined
        self._buf, self._ready, self._joined = b"", False, False
        received = len(buf)
        head = buf[:FRAME_OVERHEAD].ljust(FRAME_OVERHEAD, b"\0")
        prefix, msg_type, comm_type, reply_type = _HEAD[self._order].unpack(head)
        sent_prefix = prefix if received >= 4 else None
        body = buf[FRAME_OVERHEAD:]
        if received < FRAME_OVERHEAD:
            frame = Frame(msg_type, comm_type, reply_type, b"")
            return Turn(frame, received, None, sent_prefix, cut=True, joined=joined)
        expected = expected_size(msg_type, self._port, body, self._order)
        if expected is None:  # 3003; the rest of the buffer is dropped
            frame = Frame(msg_type, comm_type, reply_type, body)
            return Turn(frame, received, None, sent_prefix, cut=False, joined=joined)
        if received < expected:  # 3001; the bytes are dropped, not kept
            frame = Frame(msg_type, comm_type, reply_type, body)
            return Turn(frame, received, expected, sent_prefix, cut=True, joined=joined)
        frame = Frame(msg_type, comm_type, reply_type, body[: expected - FRAME_OVERHEAD])
        padded_ex = msg_type == MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX and received == RECV_SIZE
        if padded_ex:  # a whole 552-byte FULL_EX: MotoROS takes the padding as part of it
            return Turn(frame, received, RECV_SIZE, sent_prefix, cut=False, joined=joined)
        if received > expected:
            self._keep(buf[expected:])
        return Turn(frame, received, expected, sent_prefix, cut=False, joined=joined)

    def _keep(self, surplus: bytes) -> None:
        """Bytes after a message: processed next without a read when they hold a whole
        message (or an unknown type's header), else joined with the next read."""
        self._buf = surplus
        if len(surplus) < FRAME_OVERHEAD:
            return
        msg_type = _HEAD[self._order].unpack_from(surplus)[1]
        expected = expected_size(msg_type, self._port, surplus[FRAME_OVERHEAD:], self._order)
        self._ready = expected is None or len(surplus) >= expected


def turn_verdict(turn: Turn, order: ByteOrder, port: Port) -> Verdict:
    """What MotoROS does with one pass: the size rules of §1.5 on what arrived."""
    if turn.received < FRAME_OVERHEAD:
        # "Didn't even receive a command ID": 3001 whatever the partial type says.
        return Reject(short_message_reply(turn.frame, order, port), InvalidSubcode.MSGSIZE)
    return check_request(turn.frame, order, port)
