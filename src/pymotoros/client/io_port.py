"""IO bits, IO groups and M-registers: the IO part of :class:`~pymotoros.client.RobotClient`.

Addresses and values are checked against the controller's IO map before anything is
sent (``check=False`` sends them as given, to see the controller's own refusal). Bits
and groups go over the IO port, or the motion port when only that one is open (MotoROS
answers them on both); M-registers exist on the IO port only.
"""

from __future__ import annotations

from pymotoros.client import io_map
from pymotoros.client.errors import io_error, reply_error
from pymotoros.client.link import Link
from pymotoros.client.motion_commands import expect_reply
from pymotoros.models import ControllerModel
from pymotoros.protocol.constants import IoResultCode, Port
from pymotoros.protocol.messages import IoErrorReply, Message, MotoMotionReply, WireMessage
from pymotoros.protocol.messages import io as io_wire


class IoPort:
    """Reads and writes of the controller's IO image, each checked and answered."""

    def __init__(self, link: Link, controller: ControllerModel) -> None:
        self._link = link
        self._controller = controller

    async def _request(
        self, message: Message, address: int, what: str, *, io_only: bool
    ) -> WireMessage:
        conn = self._link.need(Port.IO) if io_only else self._link.io_or_motion()
        expected = io_wire.IO_REPLIES[type(message)]
        reply = await conn.request(message, expected, timeout_s=self._link.timeout_s)
        if isinstance(reply, IoErrorReply):
            raise reply_error(reply.result, reply.subcode, int(message.MSG_TYPE))
        if isinstance(reply, MotoMotionReply):
            raise reply_error(reply.result, reply.subcode, reply.command)
        code = getattr(reply, "result_code", IoResultCode.OK)
        if code != IoResultCode.OK:
            raise io_error(code, address, what)
        return reply

    async def read_io_bit(self, address: int, *, check: bool = True) -> int:
        """Read one IO bit (e.g. 10010 = general output OT#1)."""
        if check:
            io_map.check_bit_address(self._controller, address, write=False)
        reply = await self._request(
            io_wire.MotoReadIoBit(address), address, "IO read", io_only=False
        )
        return expect_reply(reply, io_wire.MotoReadIoBitReply).value

    async def write_io_bit(self, address: int, value: int, *, check: bool = True) -> None:
        """Write one IO bit (general outputs, network inputs, interface panel only)."""
        if check:
            io_map.check_bit_address(self._controller, address, write=True)
            io_map.check_bit_value(address, value)
        message = io_wire.MotoWriteIoBit(address, value)
        await self._request(message, address, "IO write", io_only=False)

    async def read_io_group(self, address: int, *, check: bool = True) -> int:
        """Read 8 bits; ``address`` is the byte number (1001 = bits 10010..10017)."""
        if check:
            io_map.check_group_address(self._controller, address, write=False)
        reply = await self._request(
            io_wire.MotoReadIoGroup(address), address, "IO group read", io_only=False
        )
        return expect_reply(reply, io_wire.MotoReadIoGroupReply).value

    async def write_io_group(self, address: int, value: int, *, check: bool = True) -> None:
        """Write 8 bits (0..255, bit 0 first) to byte ``address``."""
        if check:
            io_map.check_group_address(self._controller, address, write=True)
            io_map.check_group_value(address, value)
        message = io_wire.MotoWriteIoGroup(address, value)
        await self._request(message, address, "IO group write", io_only=False)

    async def read_mregister(self, number: int, *, check: bool = True) -> int:
        """Read M-register ``number`` (0..999; IO port only)."""
        n = io_map.normalise_mregister(number, write=False) if check else number
        reply = await self._request(
            io_wire.MotoReadMRegister(n), number, "M-register read", io_only=True
        )
        return expect_reply(reply, io_wire.MotoReadMRegisterReply).value

    async def write_mregister(self, number: int, value: int, *, check: bool = True) -> None:
        """Write M-register ``number`` (0..559) with 0..65535 (IO port only)."""
        n = number
        if check:
            n = io_map.normalise_mregister(number, write=True)
            io_map.check_mregister_value(number, value)
        message = io_wire.MotoWriteMRegister(n, value)
        await self._request(message, number, "M-register write", io_only=True)
