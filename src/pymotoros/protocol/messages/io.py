"""The IO messages: bits, groups and M-registers, and the IO port's error reply (§1.4, §1.6).

Bits and groups travel on the IO port and on the motion port (MotoROS answers
them on both); M-registers and the error reply exist on the IO port only.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import ClassVar, Final, NamedTuple, Self

from pymotoros.protocol.constants import ByteOrder, MsgType, Port
from pymotoros.protocol.messages._base import (
    I32,
    U32,
    Kind,
    Message,
    Role,
    pick,
    size_error,
    tnew,
)
from pymotoros.protocol.messages.motion import BODY_SIZE_MOTION_REPLY

__all__ = [
    "IoErrorReply",
    "MotoReadIoBit",
    "MotoReadIoBitReply",
    "MotoReadIoGroup",
    "MotoReadIoGroupReply",
    "MotoReadMRegister",
    "MotoReadMRegisterReply",
    "MotoWriteIoBit",
    "MotoWriteIoBitReply",
    "MotoWriteIoGroup",
    "MotoWriteIoGroupReply",
    "MotoWriteMRegister",
    "MotoWriteMRegisterReply",
]


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


_I32_FIELDS_ERROR: Final = (("result", I32), ("subcode", I32))


class MotoReadIoBit(Message, _Address):
    """MOTO_READ_IO_BIT (2003): read one bit at ``io_address`` (IO port, or motion port)."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_BIT
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("io_address", U32),)


class MotoReadIoBitReply(Message, _ValueResult):
    """MOTO_READ_IO_BIT_REPLY (2004): ``value`` 0/1 and an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_BIT_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("value", U32), ("result_code", U32))


class MotoWriteIoBit(Message, _AddressValue):
    """MOTO_WRITE_IO_BIT (2005): write 0/1 to ``io_address``."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_BIT
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("io_address", U32), ("io_value", U32))


class MotoWriteIoBitReply(Message, _Result):
    """MOTO_WRITE_IO_BIT_REPLY (2006): an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_BIT_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("result_code", U32),)


class MotoReadIoGroup(Message, _Address):
    """MOTO_READ_IO_GROUP (2007): read 8 bits; ``io_address`` is a byte number n (bits n·10+k)."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_GROUP
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("io_address", U32),)


class MotoReadIoGroupReply(Message, _ValueResult):
    """MOTO_READ_IO_GROUP_REPLY (2008): ``value`` 0..255 (bit 0 = LSB) and a result code."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_IO_GROUP_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("value", U32), ("result_code", U32))


class MotoWriteIoGroup(Message, _AddressValue):
    """MOTO_WRITE_IO_GROUP (2009): write ``io_value`` (≤ 0xFF) to byte ``io_address``."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_GROUP
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("io_address", U32), ("io_value", U32))


class MotoWriteIoGroupReply(Message, _Result):
    """MOTO_WRITE_IO_GROUP_REPLY (2010): an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_IO_GROUP_REPLY
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION, Port.IO)
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("result_code", U32),)


class MotoReadMRegister(Message, _Register):
    """MOTO_READ_MREGISTER (2012, IO port only): ``register_number`` M000..M999 (or +1000000)."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_MREGISTER
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.IO,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("register_number", U32),)


class MotoReadMRegisterReply(Message, _ValueResult):
    """Reply to READ_MREGISTER: reuses type 2012; a 16-bit ``value`` and a result code."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_READ_MREGISTER
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.IO,)
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("value", U32), ("result_code", U32))


class MotoWriteMRegister(Message, _RegisterValue):
    """MOTO_WRITE_MREGISTER (2013, IO port only): write ``value`` (≤ 0xFFFF), M000..M559."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_MREGISTER
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.IO,)
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (
        ("register_number", U32),
        ("value", U32),
    )


class MotoWriteMRegisterReply(Message, _Result):
    """Reply to WRITE_MREGISTER: reuses type 2013; an :class:`IoResultCode`."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_WRITE_MREGISTER
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.IO,)
    IO_RESULT: ClassVar[bool] = True
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = (("result_code", U32),)


_IO_ERROR_PADDING: Final = BODY_SIZE_MOTION_REPLY - 8  # after result and subcode
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
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.IO,)
    BODY_SIZE: ClassVar[int] = BODY_SIZE_MOTION_REPLY
    """Two int32 and 52 zero bytes: the size of a MOTION_REPLY (§1.6)."""
    FIELDS: ClassVar[tuple[tuple[str, Kind], ...]] = _I32_FIELDS_ERROR

    def pack(self, order: ByteOrder) -> bytes:
        """``result`` and ``subcode`` as int32, then 52 zero bytes (the size of a MOTION_REPLY)."""
        return pick(self._STRUCTS, order).pack(self.result, self.subcode) + bytes(_IO_ERROR_PADDING)

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """60 bytes; the trailing 52 are not checked (MotoROS leaves them zero)."""
        if len(body) != BODY_SIZE_MOTION_REPLY:
            raise size_error(cls, body, BODY_SIZE_MOTION_REPLY)
        return tnew(cls, pick(cls._STRUCTS, order).unpack_from(body))


IO_REPLIES: Final[Mapping[type[Message], type[Message]]] = MappingProxyType(
    {
        MotoReadIoBit: MotoReadIoBitReply,
        MotoWriteIoBit: MotoWriteIoBitReply,
        MotoReadIoGroup: MotoReadIoGroupReply,
        MotoWriteIoGroup: MotoWriteIoGroupReply,
        MotoReadMRegister: MotoReadMRegisterReply,
        MotoWriteMRegister: MotoWriteMRegisterReply,
    }
)
"""The reply type to each IO request (§1.4): what the client waits for. Not in
``__all__``: the registry of :mod:`pymotoros.protocol.messages` lists message classes."""
