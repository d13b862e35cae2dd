"""Hand-built Simple Message bytes for the protocol tests.

Nothing here imports the code under test: frames are assembled field by field
at the offsets of reference §1.4, with explicit ``struct`` formats, so a golden
vector can disagree with the codec.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

LE = "<"
BE = ">"
ORDERS = (LE, BE)


class Body:
    """A zero-filled body of ``size`` bytes; fields are written at explicit offsets."""

    def __init__(self, order: str, size: int) -> None:
        self.order = order
        self.data = bytearray(size)

    def i(self, offset: int, value: int) -> Body:
        struct.pack_into(self.order + "i", self.data, offset, value)
        return self

    def u(self, offset: int, value: int) -> Body:
        struct.pack_into(self.order + "I", self.data, offset, value)
        return self

    def f(self, offset: int, value: float) -> Body:
        struct.pack_into(self.order + "f", self.data, offset, value)
        return self

    def fs(self, offset: int, values: Sequence[float]) -> Body:
        for k, value in enumerate(values):
            self.f(offset + 4 * k, value)
        return self

    def record(
        self,
        offset: int,
        group: int,
        valid: int,
        time: float,
        pos: Sequence[float],
        vel: Sequence[float],
        acc: Sequence[float],
    ) -> Body:
        """A 132-byte group record: groupNo@0 validFields@4 time@8 pos@12 vel@52 acc@92."""
        self.i(offset, group).i(offset + 4, valid).f(offset + 8, time)
        return self.fs(offset + 12, pos).fs(offset + 52, vel).fs(offset + 92, acc)

    def bytes(self) -> bytes:
        return bytes(self.data)


def frame(order: str, msg_type: int, comm: int, reply: int, body: bytes = b"") -> bytes:
    """prefix (= 12 + body) + header + body."""
    return struct.pack(order + "iiii", 12 + len(body), msg_type, comm, reply) + body


def pad10(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(values) + (0.0,) * (10 - len(values))
