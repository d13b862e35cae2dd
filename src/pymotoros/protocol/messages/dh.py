"""GET_DH_PARAMETERS (2020): the empty request and the 4 × 8-link reply (§1.4)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import ClassVar, Final, NamedTuple, Self

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol.constants import MAX_DH_LINKS, MAX_GROUPS, ByteOrder, MsgType, Port
from pymotoros.protocol.messages._base import (
    Message,
    NoFields,
    Role,
    check_float,
    pick,
    size_error,
    struct_pair,
    tnew,
)

__all__ = [
    "BODY_SIZE_DH_REPLY",
    "DhLink",
    "MotoGetDhParameters",
    "MotoGetDhParametersReply",
]


class DhLink(NamedTuple):
    """Denavit–Hartenberg parameters of one link, as MotoROS reports them."""

    theta: float
    d: float
    a: float
    alpha: float


class MotoGetDhParameters(Message, NoFields):
    """MOTO_GET_DH_PARAMETERS (2020) request: empty body."""

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_GET_DH_PARAMETERS
    ROLE: ClassVar[Role] = Role.REQUEST
    REQUEST_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)


_FLOATS_PER_LINK: Final = len(DhLink._fields)
"""theta, d, a, alpha: float32 each (§1.4)."""

_DH_STRUCTS: Final = struct_pair(f"{MAX_GROUPS * MAX_DH_LINKS * _FLOATS_PER_LINK}f")

BODY_SIZE_DH_REPLY: Final = _DH_STRUCTS[0].size
"""512: 4 groups × 8 links × {theta, d, a, alpha} float32 (§1.4)."""


class _Dh(NamedTuple):
    groups: tuple[tuple[DhLink, ...], ...]


_ZERO_LINK: Final = DhLink(0.0, 0.0, 0.0, 0.0)


class MotoGetDhParametersReply(Message, _Dh):
    """The GET_DH_PARAMETERS reply (type 2020 again): 4 groups × 8 links, always.

    Groups the controller does not have are all zero (§1.4).
    """

    __slots__ = ()
    MSG_TYPE: ClassVar[MsgType] = MsgType.MOTO_GET_DH_PARAMETERS
    ROLE: ClassVar[Role] = Role.REPLY
    REPLY_ON: ClassVar[tuple[Port, ...]] = (Port.MOTION,)
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
                    check_float(owner, f"groups[{g}][{k}].{name}", value)
            checked.append(row)
        return tnew(cls, (tuple(checked),))

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
        """The body: 4 groups × 8 links × (theta, d, a, alpha) as float32, unused groups zero."""
        flat = [value for links in self.groups for link in links for value in link]
        return pick(_DH_STRUCTS, order).pack(*flat)

    @classmethod
    def unpack(cls, body: bytes, order: ByteOrder) -> Self:
        """Decode exactly one body of ``BODY_SIZE_DH_REPLY`` bytes; another size is the peer's
        fault."""
        if len(body) != BODY_SIZE_DH_REPLY:
            raise size_error(cls, body, BODY_SIZE_DH_REPLY)
        raw = pick(_DH_STRUCTS, order).unpack(body)
        step = _FLOATS_PER_LINK
        per_group = MAX_DH_LINKS * step
        groups = tuple(
            tuple(
                DhLink(*raw[base + k * step : base + (k + 1) * step]) for k in range(MAX_DH_LINKS)
            )
            for base in range(0, MAX_GROUPS * per_group, per_group)
        )
        return tnew(cls, (groups,))
