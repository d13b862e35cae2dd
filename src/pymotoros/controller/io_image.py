"""The controller's IO image: every bit of every area, and the M-registers.

Two kinds of access:

- *internal* (:meth:`IoImage.get` / :meth:`IoImage.set`): the controller itself (operator
  state, INFORM jobs, MotoROS) writes any signal without range checks;
- *client* (:meth:`IoImage.read_bit` … :meth:`IoImage.write_mregister`): the rules of
  MotoROS's IO server (reference §6.1, §6.2) with their result codes 1001..1005.

A write that changes one of the signals the status monitor reads raises
:attr:`IoImage.monitor_dirty`, so the 10 ms monitor can skip its work while nothing
it reads has changed.

Every read or write of an M-register, by anybody, first calls the
``before_mregister_access`` port the image was built with: the S1CxG register outputs
(:mod:`pymotoros.controller.registers`) keep the inputs of the latest tick and write
their words only then, so a tick pays nothing for words nobody reads. Both share the
M-register words (:func:`mregister_words`), made first by ``assembly.py``, so each part
is given what it acts on when it is built (issue 30) and nothing is hooked in later.
"""

from __future__ import annotations

import logging
from array import array
from collections.abc import Callable

from pymotoros.controller.signals import MONITORED
from pymotoros.controller.values import IoRead
from pymotoros.models import ControllerModel, IoRange
from pymotoros.models import io as rules
from pymotoros.models.controllers import M_REGISTER_BASE, M_REGISTER_COUNT
from pymotoros.protocol.constants import IoResultCode

logger = logging.getLogger(__name__)


def mregister_words() -> array[int]:
    """M000..M999 as zeroed unsigned 16-bit words: the store an :class:`IoImage` and the
    register outputs share."""
    return array("H", bytes(2 * M_REGISTER_COUNT))


class IoImage:
    """Bits addressed as Yaskawa does (byte number × 10 + bit) and M000..M999."""

    __slots__ = (
        "_before_mregister_access",
        "_bytes",
        "_controller",
        "_mreg",
        "changes",
        "fail_reads",
        "fail_writes",
        "monitor_dirty",
        "monitored_changes",
    )

    def __init__(
        self,
        controller: ControllerModel,
        *,
        mregisters: array[int] | None = None,
        before_mregister_access: Callable[[], None] | None = None,
    ) -> None:
        """``mregisters``: the M000..M999 words, shared with the part that computes some
        of them on demand (:func:`mregister_words`; a fresh zeroed set when None);
        ``before_mregister_access``: what brings those words up to date, called before
        any M-register is read or written."""
        self._controller = controller
        highest = max(r.last for r in controller.io_ranges)
        self._bytes = bytearray(highest // 10 + 1)
        self._mreg = mregister_words() if mregisters is None else mregisters
        if len(self._mreg) != M_REGISTER_COUNT:
            raise ValueError(f"mregisters: {M_REGISTER_COUNT} words, not {len(self._mreg)}")
        self._before_mregister_access = before_mregister_access
        self.monitor_dirty = True
        """Set when a signal the status monitor reads changes; the monitor clears it."""
        self.changes = 0
        """Counts every change of any bit (a cheap 'has anything changed' test)."""
        self.monitored_changes = 0
        """Counts changes of monitored signals (a cheap cache key)."""
        self.fail_reads = False
        """Fault injection: every client read fails as if the controller's API failed (1004)."""
        self.fail_writes = False
        """Fault injection: every client write fails as if the controller's API failed (1005)."""

    # ------------------------------------------------------------------ internal access

    def get(self, address: int) -> int:
        """Value (0/1) of any bit address; no range check."""
        return (self._bytes[address // 10] >> (address % 10)) & 1

    def set(self, address: int, value: int | bool) -> None:
        """Set any bit address (the controller's own writes); no range check."""
        index, bit = divmod(address, 10)
        old = self._bytes[index]
        new = (old | (1 << bit)) if value else (old & ~(1 << bit))
        if new != old:
            self._bytes[index] = new
            self.changes += 1
            if address in MONITORED:
                self.monitor_dirty = True
                self.monitored_changes += 1

    def set_mregister(self, index: int, value: int) -> None:
        self._sync_mregisters()
        self._mreg[index] = value

    def mregister(self, index: int) -> int:
        """M-register ``index`` (0..999) now; no range check."""
        self._sync_mregisters()
        return self._mreg[index]

    def _sync_mregisters(self) -> None:
        if self._before_mregister_access is not None:
            self._before_mregister_access()

    def readable_range(self, address: int) -> IoRange | None:
        """The IO range holding ``address``, or None if no readable range holds it."""
        return self._controller.io_range(address)

    # ------------------------------------------------------------------ client access (§6.1)

    def read_bit(self, address: int) -> IoRead:
        code = rules.bit_address_result(self._controller, address, write=False)
        return self._client_read(code, lambda: self.get(address))

    def write_bit(self, address: int, value: int) -> IoResultCode:
        code = rules.bit_address_result(self._controller, address, write=True)
        code = code or rules.bit_value_result(value)
        return self._client_write(code, lambda: self.set(address, value))

    def read_group(self, number: int) -> IoRead:
        """Byte ``number``: bits number×10+0..7, bit 0 least significant (§6.1)."""
        code = rules.group_address_result(self._controller, number, write=False)
        return self._client_read(code, lambda: self._bytes[number])

    def write_group(self, number: int, value: int) -> IoResultCode:
        code = rules.group_address_result(self._controller, number, write=True)
        code = code or rules.group_value_result(value)
        return self._client_write(code, lambda: self._set_group(number, value))

    def read_mregister(self, number: int) -> IoRead:
        code = rules.mregister_address_result(number, write=False)
        return self._client_read(code, lambda: self.mregister(rules.m_register_index(number)))

    def write_mregister(self, number: int, value: int) -> IoResultCode:
        code = rules.mregister_address_result(number, write=True)
        code = code or rules.mregister_value_result(value)
        index = rules.m_register_index(number)
        return self._client_write(code, lambda: self.set_mregister(index, value))

    def set_api_failure(self, *, reads: bool, writes: bool) -> None:
        """Fault injection: make client reads (1004) and/or writes (1005) fail."""
        self.fail_reads = reads
        self.fail_writes = writes

    def _client_read(self, code: IoResultCode, value: Callable[[], int]) -> IoRead:
        """A client read: the address's refusal, the injected API failure, or the value."""
        if code:
            return IoRead(0, code)
        if self.fail_reads:
            return IoRead(0, IoResultCode.READ_API_ERROR)
        return IoRead(value(), IoResultCode.OK)

    def _client_write(self, code: IoResultCode, write: Callable[[], None]) -> IoResultCode:
        """A client write: the refusal, the injected API failure, or done."""
        if code:
            return code
        if self.fail_writes:
            return IoResultCode.WRITE_API_ERROR
        write()
        return IoResultCode.OK

    def _set_group(self, number: int, value: int) -> None:
        first = number * 10
        for k in range(rules.GROUP_BITS):
            self.set(first + k, (value >> k) & 1)

    # ------------------------------------------------------------------ operator access

    def read_any(self, address: int) -> int:
        """A bit's value, or M-register n's at ``1000000 + n`` (scenario conditions)."""
        if address >= M_REGISTER_BASE:
            return self.read_mregister(address - M_REGISTER_BASE).value
        return self.get(address)

    def check_forcible(self, address: int, value: int) -> None:
        """Raise ``ValueError`` unless the operator may force ``address`` to ``value``.

        Any readable bit address takes 0/1; ``1000000 + n`` (n = 0..999) is M-register n
        and takes 0..65535.
        """
        if address >= M_REGISTER_BASE:
            index = address - M_REGISTER_BASE
            if not 0 <= index < M_REGISTER_COUNT:
                raise ValueError(
                    f"M-register address {address}: only {M_REGISTER_BASE}.."
                    f"{M_REGISTER_BASE + M_REGISTER_COUNT - 1} (M000..M999) exist"
                )
            if rules.mregister_value_result(value):
                raise ValueError(f"M{index:03d} holds 0..{rules.M_REGISTER_MAX}, not {value}")
            return
        if self._controller.io_range(address) is None:
            raise ValueError(
                f"address {address} is in no IO range of a {self._controller.type.value} "
                "controller (or its last digit is 8 or 9)"
            )
        if rules.bit_value_result(value):
            raise ValueError(f"bit {address} takes 0 or 1, not {value}")
