"""The state port's topics: ROBOT_STATUS, JOINT_FEEDBACK and JOINT_FEEDBACK_EX (§1.4, §2).

The state server sends them every cycle and never reads its sockets; the motion
server decodes them too, only to size them and close the connection (§1.5).
The 132-byte group record of JOINT_FEEDBACK is also one slot of FEEDBACK_EX and
of JOINT_TRAJ_PT_FULL_EX (:mod:`.trajectory`).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable
from typing import ClassVar, Final, NamedTuple, Self

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol.constants import MAX_GROUPS, ByteOrder, MsgType, Port, ValidFields
from pymotoros.protocol.messages._base import (
    F32,
    I32,
    JOINTS,
    ZERO_JOINTS,
    Kind,
    Message,
    Role,
    bind_joint_record,
    check_int,
    pad_arrays,
    pick,
    size_error,
    struct_pair,
    tnew,
)

__all__ = [
    "BODY_SIZE_FEEDBACK_EX",
    "BODY_SIZE_GROUP_RECORD",
    "JointFeedback",
    "MotoJointFeedbackEx",
    "RobotStatus",
]


class _Status(NamedTuple):
    drives_powered: int
    e_stopped: int
    error_code: int
    in_error: int
    in_motion: int
    mode: int
    motion_possible: int


class RobotStatus(Message, _Status):
    """ROBOT_STATUS (13): seven int32 status fields, sent every state cycle (§2.6).

    Tri-state fields are 1/0 (-1 "unknown" only for a rare ``in_motion``);
    ``mode`` is 1 (manual/teach) or 2 (auto/play).
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.ROBOT_STATUS
    ROLE: ClassVar[Role] = Role.TOPIC
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.STATE,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = tuple((name, I32) for name in _Status._fields)


class GroupRecord(NamedTuple):
    group_no: int
    valid_fields: int
    time: float
    pos: tuple[float, ...]
    vel: tuple[float, ...]
    acc: tuple[float, ...] = ZERO_JOINTS


GROUP_RECORD_FIELDS: Final[tuple[tuple[str, Kind], ...]] = (
    ("group_no", I32),
    ("valid_fields", I32),
    ("time", F32),
    ("pos", JOINTS),
    ("vel", JOINTS),
    ("acc", JOINTS),
)

# pos, vel and acc end the 132-byte group record, at offsets 12, 52 and 92 (§1.4).


_FEEDBACK_FLAGS: Final = int(ValidFields.POSITION)
_FEEDBACK_FLAGS_VEL: Final = int(ValidFields.POSITION | ValidFields.VELOCITY)
"""JOINT_FEEDBACK's default flags as plain ints, computed once (the state server builds
one per group every cycle; ``IntFlag`` operators are Python calls)."""


class JointFeedback(Message, GroupRecord):
    """JOINT_FEEDBACK (15): one group's feedback position (rad or m) and speed.

    MotoROS sends ``valid_fields`` 6 (position + velocity), ``time`` 0.0 and ``acc``
    zeros (§2.4). Arrays are in ROS joint order, 10 slots, slots 8 and 9 zero.
    The same 132-byte layout is one slot of JOINT_FEEDBACK_EX.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.JOINT_FEEDBACK
    ROLE: ClassVar[Role] = Role.TOPIC
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.STATE,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = GROUP_RECORD_FIELDS

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
            valid_fields = _FEEDBACK_FLAGS_VEL if vel is not None else _FEEDBACK_FLAGS
        return cls(group_no, int(valid_fields), time, *pad_arrays(cls.__name__, pos, vel, acc))

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
        """Decode exactly one body of this type; a wrong size is the peer's fault."""
        return cls.unpack_from(body, 0, len(body), order)

    @classmethod
    def _bind_unpack_from(cls, order: ByteOrder) -> Callable[[bytes, int, int], JointFeedback]:
        """The only JOINT_FEEDBACK decoder: the client's per-frame work on the state port.

        ``next_reply``, ``decode_reply``, :meth:`unpack_from`, :meth:`unpack` and
        FEEDBACK_EX's slots all come here: :func:`._base.bind_joint_record`.
        """
        if order == ">":
            return bind_joint_record(cls, _RECORD_HEAD_BE, _JOINTS_BE, BODY_SIZE_GROUP_RECORD)
        return bind_joint_record(cls, _RECORD_HEAD_LE, _JOINTS_LE, BODY_SIZE_GROUP_RECORD)


_RECORD_LE, _RECORD_BE = JointFeedback._STRUCTS
_RECORD_HEAD_LE, _RECORD_HEAD_BE = struct_pair("iif")  # groupNo, validFields, time
_JOINTS_LE, _JOINTS_BE = struct_pair(JOINTS.value)

BODY_SIZE_GROUP_RECORD: Final = JointFeedback.BODY_SIZE
"""132: groupNo, validFields, time, pos[10], vel[10], acc[10]: the JOINT_FEEDBACK body and
the per-group record of FULL_EX / FEEDBACK_EX (§1.4)."""


def group_count(n: int) -> int:
    """How many 132-byte records a message with ``numberOfValidGroups = n`` carries."""
    return min(max(n, 0), MAX_GROUPS)


def check_records(owner: str, n: int, groups: tuple[object, ...], kind: type) -> None:
    check_int(owner, "number_of_valid_groups", n, I32)
    if len(groups) != group_count(n):
        raise LocalProtocolError(
            f"{owner}: number_of_valid_groups {n} needs {group_count(n)} records, got {len(groups)}"
        )
    if not all(isinstance(g, kind) for g in groups):
        raise LocalProtocolError(f"{owner}.groups must hold {kind.__name__} records")


class _FeedbackEx(NamedTuple):
    number_of_valid_groups: int
    groups: tuple[JointFeedback, ...]


_EX_COUNT_STRUCTS: Final = struct_pair("i")

BODY_SIZE_FEEDBACK_EX: Final = _EX_COUNT_STRUCTS[0].size + MAX_GROUPS * BODY_SIZE_GROUP_RECORD
"""532: numberOfValidGroups + always four 132-byte slots (§1.3)."""


class MotoJointFeedbackEx(Message, _FeedbackEx):
    """MOTO_JOINT_FEEDBACK_EX (2017): every group's feedback in one message.

    Always 4 slots on the wire (532-byte body); slots past ``groups`` are zero.
    ``groups`` holds ``clamp(n, 0, 4)`` :class:`JointFeedback` records.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_JOINT_FEEDBACK_EX
    ROLE: ClassVar[Role] = Role.TOPIC
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.STATE,)
    BODY_SIZE: ClassVar[int] = BODY_SIZE_FEEDBACK_EX

    @classmethod
    def _validated(cls, message: Self) -> Self:
        groups = tuple(message.groups)
        check_records(cls.__name__, message.number_of_valid_groups, groups, JointFeedback)
        return tnew(cls, (message.number_of_valid_groups, groups))

    @classmethod
    def for_groups(cls, groups: Iterable[JointFeedback]) -> Self:
        """n = the number of records given (at most 4)."""
        records = tuple(groups)
        if len(records) > MAX_GROUPS:
            raise LocalProtocolError(f"{cls.__name__}: {len(records)} groups, at most {MAX_GROUPS}")
        return cls(len(records), records)

    def pack(self, order: ByteOrder) -> bytes:
        """The count, the groups' records, then zeros up to ``BODY_SIZE_FEEDBACK_EX`` (MotoROS's
        fixed size)."""
        head = pick(_EX_COUNT_STRUCTS, order).pack(self.number_of_valid_groups)
        slots = b"".join(record.pack(order) for record in self.groups)
        return head + slots + bytes(BODY_SIZE_FEEDBACK_EX - len(head) - len(slots))

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """Decode exactly ``BODY_SIZE_FEEDBACK_EX`` bytes: the count, then the group records."""
        if len(body) != BODY_SIZE_FEEDBACK_EX:
            raise size_error(cls, body, BODY_SIZE_FEEDBACK_EX)
        head = pick(_EX_COUNT_STRUCTS, order)
        (n,) = head.unpack_from(body)
        end = head.size + group_count(n) * BODY_SIZE_GROUP_RECORD
        records = tuple(
            JointFeedback.unpack_from(body, start, start + BODY_SIZE_GROUP_RECORD, order)
            for start in range(head.size, end, BODY_SIZE_GROUP_RECORD)
        )
        return tnew(cls, (n, records))
