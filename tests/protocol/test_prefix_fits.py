"""``prefix_fits``: the one length-prefix check of the recording reader and the client's hint."""

from __future__ import annotations

import struct

from pymotoros.protocol.constants import HEADER_SIZE, MAX_LENGTH_PREFIX, ByteOrder
from pymotoros.protocol.framing import prefix_fits


def test_a_prefix_fits_in_its_own_byte_order_only() -> None:
    little = struct.pack("<i", HEADER_SIZE) + bytes(HEADER_SIZE)
    assert prefix_fits(little, ByteOrder.LITTLE)
    assert not prefix_fits(little, ByteOrder.BIG)
    assert prefix_fits(struct.pack(">i", MAX_LENGTH_PREFIX), ByteOrder.BIG)


def test_out_of_range_or_short_data_does_not_fit() -> None:
    assert not prefix_fits(struct.pack("<i", HEADER_SIZE - 1), ByteOrder.LITTLE)
    assert not prefix_fits(struct.pack("<i", MAX_LENGTH_PREFIX + 1), ByteOrder.LITTLE)
    assert not prefix_fits(b"\x0c\x00\x00", ByteOrder.LITTLE)
