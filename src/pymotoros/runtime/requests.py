"""MotoROS's size-by-type decision for one received frame (reference §1.5), server side.

MotoROS sizes an incoming message by its ``msg_type`` alone. For one frame this
module decides what a MotoROS server does with it: decode it (surplus bytes
trimmed), answer INVALID/3003 (unknown type), answer INVALID/3001 (shorter than
the type requires), or close the connection (types the motion server sizes but
does not process: 13, 15, 2002, 2017).
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final

from pymotoros.protocol.constants import (
    ByteOrder,
    InvalidSubcode,
    MsgType,
    Port,
)
from pymotoros.protocol.framing import Frame, decode_request
from pymotoros.protocol.messages import (
    BODY_SIZE_FEEDBACK_EX,
    BODY_SIZE_FULL_EX_HEAD,
    BODY_SIZE_GROUP_RECORD,
    BODY_SIZE_MOTION_REPLY,
    WireMessage,
)

__all__ = ["CLOSING_TYPES", "Checked", "check_request", "expected_body_size"]

_MOTION_SIZES: Final[Mapping[int, int]] = MappingProxyType(
    {
        MsgType.PING: 0,
        MsgType.ROBOT_STATUS: 28,
        MsgType.JOINT_TRAJ_PT_FULL: 136,
        MsgType.JOINT_FEEDBACK: BODY_SIZE_GROUP_RECORD,
        MsgType.MOTO_MOTION_CTRL: 52,
        MsgType.MOTO_MOTION_REPLY: BODY_SIZE_MOTION_REPLY,
        MsgType.MOTO_JOINT_FEEDBACK_EX: BODY_SIZE_FEEDBACK_EX,
        MsgType.MOTO_READ_IO_BIT: 4,
        MsgType.MOTO_WRITE_IO_BIT: 8,
        MsgType.MOTO_READ_IO_GROUP: 4,
        MsgType.MOTO_WRITE_IO_GROUP: 8,
        MsgType.MOTO_GET_DH_PARAMETERS: 0,
        MsgType.MOTO_SELECT_TOOL: 12,
    }
)
"""Body sizes the motion server expects by type (§1.5); 2016 is computed from n."""

_IO_SIZES: Final[Mapping[int, int]] = MappingProxyType(
    {
        MsgType.MOTO_READ_IO_BIT: 4,
        MsgType.MOTO_WRITE_IO_BIT: 8,
        MsgType.MOTO_READ_IO_GROUP: 4,
        MsgType.MOTO_WRITE_IO_GROUP: 8,
        MsgType.MOTO_READ_MREGISTER: 4,
        MsgType.MOTO_WRITE_MREGISTER: 8,
    }
)
"""Body sizes the IO server expects by type (§1.5): only the six IO types."""

CLOSING_TYPES: Final = frozenset(
    {
        MsgType.ROBOT_STATUS,
        MsgType.JOINT_FEEDBACK,
        MsgType.MOTO_MOTION_REPLY,
        MsgType.MOTO_JOINT_FEEDBACK_EX,
    }
)
"""Known sizes that the motion server does not process: the connection is closed (§1.5)."""

_FULL_EX_UNKNOWN_N_BODY: Final = 552 - 16
"""FULL_EX with fewer than 4 body bytes (n unreadable) is sized as the full 552 bytes."""

_ECHOING_TYPES: Final[Mapping[int, int]] = MappingProxyType(
    {
        # type -> body offset of the sequence field echoed in a 3001 reply
        MsgType.MOTO_MOTION_CTRL: 4,
        MsgType.JOINT_TRAJ_PT_FULL: 4,
        MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX: 4,
        MsgType.MOTO_SELECT_TOOL: 8,
    }
)
"""Types whose short-message reply carries group 0 and the echoed sequence/command (§1.5)."""


@dataclass(frozen=True, slots=True)
class Checked:
    """What a server does with one frame."""

    message: WireMessage | None = None
    """The decoded request (surplus trimmed), when it is to be processed."""
    error_subcode: int | None = None
    """3001 or 3003 when the answer is an INVALID reply instead."""
    close: bool = False
    """True: close the connection without replying (motion port, types 13/15/2002/2017)."""
    reply_group: int = -1
    reply_sequence: int = -1
    reply_command: int = 0
    """Group, sequence and command of the motion port's INVALID reply."""
    reason: str = ""
    trimmed: int = 0
    """Surplus body bytes ignored."""


def expected_body_size(msg_type: int, body: bytes, order: ByteOrder, port: Port) -> int | None:
    """The body size MotoROS expects for ``msg_type`` on ``port``; None if it does not know it."""
    if port is Port.IO:
        return _IO_SIZES.get(msg_type)
    if port is not Port.MOTION:
        return None
    if msg_type == MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX:
        if len(body) < 4:
            return _FULL_EX_UNKNOWN_N_BODY
        (n,) = struct.unpack_from(f"{order}i", body)
        return BODY_SIZE_FULL_EX_HEAD + BODY_SIZE_GROUP_RECORD * max(int(n), 0)
    return _MOTION_SIZES.get(msg_type)


def _echo(frame: Frame, order: ByteOrder) -> tuple[int, int, int]:
    """Group, sequence and command of a short message's 3001 reply (missing bytes read 0)."""
    offset = _ECHOING_TYPES.get(frame.msg_type)
    if offset is None:
        return -1, -1, frame.msg_type
    padded = frame.body.ljust(offset + 8, b"\0")
    sequence, word = struct.unpack_from(f"{order}ii", padded, offset)
    command = word if frame.msg_type == MsgType.MOTO_MOTION_CTRL else frame.msg_type
    return 0, sequence, command


def check_request(frame: Frame, order: ByteOrder, port: Port) -> Checked:
    """Apply §1.5 to one frame received on ``port`` (motion or IO)."""
    body = frame.body
    expected = expected_body_size(frame.msg_type, body, order, port)
    if expected is None:
        return Checked(
            error_subcode=InvalidSubcode.MSGTYPE,
            reply_command=frame.msg_type,
            reason=f"type {frame.msg_type} is not served on the {port.value} port",
        )
    if len(body) < expected:
        group, sequence, command = (
            _echo(frame, order) if port is Port.MOTION else (-1, -1, frame.msg_type)
        )
        return Checked(
            error_subcode=InvalidSubcode.MSGSIZE,
            reply_group=group,
            reply_sequence=sequence,
            reply_command=command,
            reason=f"type {frame.msg_type} needs a {expected}-byte body, got {len(body)}",
        )
    if port is Port.MOTION and frame.msg_type in CLOSING_TYPES:
        return Checked(
            close=True,
            reason=f"type {frame.msg_type} ({MsgType.describe(frame.msg_type)}) is not a request",
        )
    surplus = len(body) - expected
    if surplus:
        frame = frame._replace(body=body[:expected])
    return Checked(message=decode_request(frame, order, port), trimmed=surplus)
