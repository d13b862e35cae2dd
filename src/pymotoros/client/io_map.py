"""IO and M-register addresses checked on the PC, before anything is sent (reference §6).

MotoROS refuses a bad address with a bare result code (1001/1002/1003); checking
here lets the error say which range applies on the chosen controller model. Whether a
request passes is decided by :mod:`pymotoros.models.io`, the rules the virtual
controller's IO server answers with; this module only explains a refusal.
"""

from __future__ import annotations

from pymotoros.client.errors import IoAddressError
from pymotoros.models import ControllerModel, IoRange
from pymotoros.models.controllers import M_REGISTER_COUNT, M_REGISTER_WRITABLE
from pymotoros.models.io import (
    GROUP_MAX,
    M_REGISTER_MAX,
    bit_address_result,
    bit_value_result,
    group_address_result,
    group_value_result,
    m_register_index,
    mregister_address_result,
    mregister_value_result,
)
from pymotoros.protocol.constants import IoResultCode


def _ranges_text(ranges: tuple[IoRange, ...]) -> str:
    return ", ".join(f"{r.area.value} {r.first}-{r.last}" for r in ranges)


def _writable(controller: ControllerModel) -> tuple[IoRange, ...]:
    return tuple(r for r in controller.io_ranges if r.writable)


def _refuse(address: int, code: IoResultCode, text: str) -> IoAddressError:
    return IoAddressError(text, address=address, result_code=int(code), remedy=text)


def check_bit_address(controller: ControllerModel, address: int, *, write: bool) -> IoRange:
    """The range holding a bit ``address``; raises :class:`IoAddressError` with the reason."""
    code = bit_address_result(controller, address, write=write)
    rng = controller.io_range(address)
    if not code and rng is not None:
        return rng
    if address < 0:
        raise _refuse(address, code, f"IO address {address} is negative")
    if address % 10 > 7:
        raise _refuse(
            address,
            code,
            f"IO address {address}: the last digit is the bit number and must be 0..7 "
            f"(bits of byte {address // 10} are {address // 10 * 10}..{address // 10 * 10 + 7})",
        )
    if rng is None:
        raise _refuse(
            address,
            code,
            f"IO address {address} is in no range of a {controller.type.value} controller; "
            f"ranges: {_ranges_text(controller.io_ranges)}",
        )
    raise _refuse(
        address,
        code,
        f"IO address {address} is in the {rng.area.value} range ({rng.first}-{rng.last}), "
        f"which MotoROS does not write; writable on {controller.type.value}: "
        f"{_ranges_text(_writable(controller))}",
    )


def check_group_address(controller: ControllerModel, address: int, *, write: bool) -> IoRange:
    """A group (byte) address n covers bits n×10..n×10+7; n×10 must be valid (§6.1)."""
    code = group_address_result(controller, address, write=write)
    if code and address < 0:
        raise _refuse(address, code, f"IO group address {address} is negative")
    try:
        return check_bit_address(controller, address * 10, write=write)
    except IoAddressError as exc:
        text = (
            f"IO group {address} (bits {address * 10}..{address * 10 + 7}): {exc}; a group "
            "address is the bit address without its last digit (1001 = 10010..10017)"
        )
        raise _refuse(address, IoResultCode(exc.result_code), text) from None


def _refuse_value(address: int, text: str) -> IoAddressError:
    """A value MotoROS would refuse with WRITE_VALUE_INVALID; ``text`` says the range."""
    return _refuse(address, IoResultCode.WRITE_VALUE_INVALID, text)


def check_bit_value(address: int, value: int) -> None:
    if bit_value_result(value):
        raise _refuse_value(address, f"IO bit {address}: value must be 0 or 1")


def check_group_value(address: int, value: int) -> None:
    if group_value_result(value):
        raise _refuse_value(address, f"IO group {address}: value must be 0..{GROUP_MAX}")


def normalise_mregister(number: int, *, write: bool) -> int:
    """M-register number 0..999 (or 1000000+n, which MotoROS also accepts); returns n."""
    code = mregister_address_result(number, write=write)
    if code:
        what = "written" if write else "read"
        raise _refuse(
            number,
            code,
            f"M-register {number}: MotoROS lets a client read M000-M{M_REGISTER_COUNT - 1} and "
            f"write M000-M{M_REGISTER_WRITABLE - 1}; this one cannot be {what} "
            "(give the plain number, e.g. 10 for M010)",
        )
    return m_register_index(number)


def check_mregister_value(number: int, value: int) -> None:
    if mregister_value_result(value):
        raise _refuse_value(number, f"M-register {number}: value must be 0..{M_REGISTER_MAX}")
