"""MotoROS's IO server rules (reference §6.1, §6.2): which address and value it takes.

One home for the controller's IO image (which answers with these result codes) and the
client's pre-flight (which refuses before sending and explains why): each function
returns the :class:`~pymotoros.protocol.constants.IoResultCode` MotoROS answers, OK
when it lets the request through. The address ranges themselves are the controller
model's (:attr:`ControllerModel.io_ranges`).
"""

from __future__ import annotations

from typing import Final

from pymotoros.models.controllers import (
    M_REGISTER_BASE,
    M_REGISTER_COUNT,
    M_REGISTER_WRITABLE,
    ControllerModel,
)
from pymotoros.protocol.constants import IoResultCode

BIT_VALUES: Final = (0, 1)
"""A bit write takes 0 or 1 (§6.1)."""

GROUP_BITS: Final = 8
"""An IO group is one byte: eight consecutive bit addresses (§6.1)."""

GROUP_MAX: Final = (1 << GROUP_BITS) - 1
"""A group (byte) write must be ≤ 0xFF (§6.1)."""

M_REGISTER_MAX: Final = 0xFFFF
"""M-registers hold 16 bits (§6.1)."""

_OK: Final = IoResultCode.OK


def _address_code(write: bool) -> IoResultCode:
    return IoResultCode.WRITE_ADDRESS_INVALID if write else IoResultCode.READ_ADDRESS_INVALID


def bit_address_result(controller: ControllerModel, address: int, *, write: bool) -> IoResultCode:
    """A bit address must lie in a range of the controller (last digit 0..7); a write
    needs a writable range (general outputs, network inputs, interface panel)."""
    rng = controller.io_range(address)
    if rng is None or (write and not rng.writable):
        return _address_code(write)
    return _OK


def group_address_result(controller: ControllerModel, number: int, *, write: bool) -> IoResultCode:
    """Group (byte) ``number`` covers bits number×10..number×10+7; number×10 decides."""
    if number < 0:
        return _address_code(write)
    return bit_address_result(controller, number * 10, write=write)


def m_register_index(number: int) -> int:
    """MotoROS's adjustment: numbers below 1000000 get 1000000 added (§6.1); index 0..."""
    if number < M_REGISTER_BASE:
        number += M_REGISTER_BASE
    return number - M_REGISTER_BASE


def mregister_address_result(number: int, *, write: bool) -> IoResultCode:
    """M000..M999 are readable, M000..M559 writable (as n or 1000000 + n, §6.1)."""
    index = m_register_index(number)
    if not 0 <= index < (M_REGISTER_WRITABLE if write else M_REGISTER_COUNT):
        return _address_code(write)
    return _OK


def bit_value_result(value: int) -> IoResultCode:
    return _OK if value in BIT_VALUES else IoResultCode.WRITE_VALUE_INVALID


def group_value_result(value: int) -> IoResultCode:
    return _OK if 0 <= value <= GROUP_MAX else IoResultCode.WRITE_VALUE_INVALID


def mregister_value_result(value: int) -> IoResultCode:
    return _OK if 0 <= value <= M_REGISTER_MAX else IoResultCode.WRITE_VALUE_INVALID
