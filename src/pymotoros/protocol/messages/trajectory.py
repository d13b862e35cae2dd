"""Trajectory points: JOINT_TRAJ_PT_FULL, and JOINT_TRAJ_PT_FULL_EX with its records (§1.4, §3.4).

All are motion-port requests; the client sends one per point, so the motion
server decodes JOINT_TRAJ_PT_FULL on its hot path.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Mapping
from typing import ClassVar, Final, NamedTuple, Self

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol.constants import (
    HEADER_SIZE,
    MAX_GROUPS,
    MAX_MESSAGE_SIZE,
    PREFIX_SIZE,
    ByteOrder,
    MsgType,
    Port,
    ValidFields,
)
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
    field_offsets,
    pad_arrays,
    pick,
    size_error,
    struct_pair,
    tnew,
)
from pymotoros.protocol.messages.state import (
    BODY_SIZE_GROUP_RECORD,
    GROUP_RECORD_FIELDS,
    GroupRecord,
    check_records,
    group_count,
)

__all__ = [
    "BODY_SIZE_FULL_EX_HEAD",
    "BODY_SIZE_TRAJ_PT_FULL",
    "FULL_EX_SIZE_UNKNOWN_BELOW",
    "JointTrajPtExData",
    "JointTrajPtFull",
    "MotoJointTrajPtFullEx",
]


class JointTrajPtExData(Message, GroupRecord):
    """One group's record inside JOINT_TRAJ_PT_FULL_EX: a point without its own sequence.

    Not a message on its own (``MSG_TYPE`` is that of the carrying FULL_EX); the
    layout is the 132-byte group record of §1.4.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    ROLE: ClassVar[Role] = Role.REQUEST
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = GROUP_RECORD_FIELDS

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
        return cls(group_no, int(valid_fields), time, *pad_arrays(cls.__name__, pos, vel, acc))


_POINT_FLAGS: Final = int(ValidFields.TIME | ValidFields.POSITION | ValidFields.VELOCITY)
_POINT_FLAGS_ACC: Final = int(_POINT_FLAGS | ValidFields.ACCELERATION)
"""The default flags as plain ints, computed once (``IntFlag`` operators are Python calls,
and the client builds a point per trajectory sample)."""


def _point_flags(acc: object) -> int:
    return _POINT_FLAGS_ACC if acc is not None else _POINT_FLAGS


# pos, vel and acc end the JOINT_TRAJ_PT_FULL body, at offsets 16, 56 and 96 (§1.4).


class _Point(NamedTuple):
    group_no: int
    sequence: int
    valid_fields: int
    time: float
    pos: tuple[float, ...]
    vel: tuple[float, ...]
    acc: tuple[float, ...] = ZERO_JOINTS


class JointTrajPtFull(Message, _Point):
    """JOINT_TRAJ_PT_FULL (14): one trajectory point for one group (§3.4).

    MotoROS needs ``valid_fields`` to contain TIME, POSITION and VELOCITY (else
    3015) and ignores ``acc``. Arrays are in ROS joint order (rad or m, rad/s or
    m/s); ``time`` is seconds from the trajectory start.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.JOINT_TRAJ_PT_FULL
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (
        ("group_no", I32),
        ("sequence", I32),
        ("valid_fields", I32),
        ("time", F32),
        ("pos", JOINTS),
        ("vel", JOINTS),
        ("acc", JOINTS),
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
        arrays = pad_arrays(cls.__name__, pos, vel, acc)
        return cls(group_no, sequence, int(valid_fields), time, *arrays)

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
        """Decode exactly one body of this type; a wrong size is the peer's fault."""
        return cls.unpack_from(body, 0, len(body), order)

    @classmethod
    def _bind_unpack_from(cls, order: ByteOrder) -> Callable[[bytes, int, int], JointTrajPtFull]:
        """The only JOINT_TRAJ_PT_FULL decoder: the motion server's per-point work.

        Hand-unrolled, no validation (see :mod:`._base`); the Structs' bound
        methods are picked once here, per byte order.
        """
        if order == ">":
            return bind_joint_record(cls, _POINT_HEAD_BE, _JOINTS_BE, BODY_SIZE_TRAJ_PT_FULL)
        return bind_joint_record(cls, _POINT_HEAD_LE, _JOINTS_LE, BODY_SIZE_TRAJ_PT_FULL)


_POINT_LE, _POINT_BE = JointTrajPtFull._STRUCTS
_POINT_HEAD_LE, _POINT_HEAD_BE = struct_pair("iiif")  # groupNo, sequence, validFields, time
_JOINTS_LE, _JOINTS_BE = struct_pair(JOINTS.value)

BODY_SIZE_TRAJ_PT_FULL: Final = JointTrajPtFull.BODY_SIZE
"""136: groupNo, sequence, validFields, time, pos[10], vel[10], acc[10] (§1.4)."""

_EX_HEAD_FIELDS: Final[tuple[tuple[str, Kind], ...]] = (
    ("number_of_valid_groups", I32),
    ("sequence", I32),
)
_EX_HEAD_STRUCTS: Final = struct_pair("".join(kind.value for _name, kind in _EX_HEAD_FIELDS))

BODY_SIZE_FULL_EX_HEAD: Final = _EX_HEAD_STRUCTS[0].size
"""8: numberOfValidGroups + sequence in front of the FULL_EX records (§1.4)."""

_EX_COUNT_STRUCTS: Final = struct_pair(I32.value)
"""numberOfValidGroups alone (all that is certain to be there past the 20 bytes below)."""

_FRAME_OVERHEAD: Final = PREFIX_SIZE + HEADER_SIZE
"""16: what framing.FRAME_OVERHEAD says (framing imports this package, not the reverse)."""

FULL_EX_SIZE_UNKNOWN_BELOW: Final = 20
"""With fewer total bytes than this, MotoROS cannot read n and expects the full 552 (§1.5)."""


class _FullEx(NamedTuple):
    number_of_valid_groups: int
    sequence: int
    groups: tuple[JointTrajPtExData, ...]


class MotoJointTrajPtFullEx(Message, _FullEx):
    """MOTO_JOINT_TRAJ_PT_FULL_EX (2016): one point for several groups, one sequence.

    The body is 8 + 132·n bytes. ``number_of_valid_groups`` is kept as sent
    (MotoROS answers n ≤ 0 or a bad group itself), so ``groups`` holds
    ``clamp(n, 0, 4)`` records. Use :meth:`for_groups` to set n from the records.
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
    BODY_SIZE: ClassVar[int] = BODY_SIZE_FULL_EX_HEAD
    """The minimum: the head with n = 0."""
    FIXED_SIZE: ClassVar[bool] = False
    OFFSETS: ClassVar[Mapping[str, int]] = field_offsets(_EX_HEAD_FIELDS)

    @classmethod
    def needed_body_size(cls, body: bytes, order: ByteOrder) -> int:
        """8 + 132·n with n read from the body; all of MAX_MESSAGE_SIZE while n is not there.

        A negative n counts as 0 (MotoROS computes a size below the header and
        then reads outside its buffer; we do not copy that).
        """
        if _FRAME_OVERHEAD + len(body) < FULL_EX_SIZE_UNKNOWN_BELOW:
            return MAX_MESSAGE_SIZE - _FRAME_OVERHEAD
        n: int = pick(_EX_COUNT_STRUCTS, order).unpack_from(body)[0]
        return BODY_SIZE_FULL_EX_HEAD + max(n, 0) * BODY_SIZE_GROUP_RECORD

    @classmethod
    def _validated(cls, message: Self) -> Self:
        owner = cls.__name__
        groups = tuple(message.groups)
        check_records(owner, message.number_of_valid_groups, groups, JointTrajPtExData)
        check_int(owner, "sequence", message.sequence, I32)
        return tnew(cls, (message.number_of_valid_groups, message.sequence, groups))

    @classmethod
    def for_groups(cls, sequence: int, groups: Iterable[JointTrajPtExData]) -> Self:
        """n = the number of records given (at most 4)."""
        records = tuple(groups)
        if len(records) > MAX_GROUPS:
            raise LocalProtocolError(f"{cls.__name__}: {len(records)} groups, at most {MAX_GROUPS}")
        return cls(len(records), sequence, records)

    def pack(self, order: ByteOrder) -> bytes:
        """The count and sequence (int32), then one record per group, no padding."""
        head = pick(_EX_HEAD_STRUCTS, order).pack(self.number_of_valid_groups, self.sequence)
        return head + b"".join(record.pack(order) for record in self.groups)

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """Exactly 8 + 132·clamp(n, 0, 4) bytes (sizes.py trims MotoROS's padded 552)."""
        head = pick(_EX_HEAD_STRUCTS, order)
        if len(body) < head.size:
            raise size_error(cls, body, f"at least {head.size}")
        n, sequence = head.unpack_from(body)
        count = group_count(n)
        expected = head.size + count * BODY_SIZE_GROUP_RECORD
        if len(body) != expected:
            raise size_error(cls, body, f"{expected} for numberOfValidGroups {n}")
        records = tuple(
            JointTrajPtExData.unpack(body[start : start + BODY_SIZE_GROUP_RECORD], order)
            for start in range(head.size, expected, BODY_SIZE_GROUP_RECORD)
        )
        return tnew(cls, (n, sequence, records))
