"""The IO server (port 50242, one client) and the IO request handling it shares with the
motion port (reference §6.1).

Bit and group reads/writes are served on both ports; M-register messages only here.
Protocol errors (unknown type, short message) get the IO error reply of §1.6: type
2002 with ``result`` at body offset 0 and ``subcode`` at 4. A reply is always sent,
whatever the request's comm_type, and the connection is always kept.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable
from typing import Final, Unpack

from pymotoros.controller.api import IoRead, MotoRosController
from pymotoros.controller.lint import LintCode
from pymotoros.models.fidelity import Fidelity
from pymotoros.protocol.constants import (
    ByteOrder,
    InvalidSubcode,
    IoResultCode,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import Frame
from pymotoros.protocol.messages import (
    IoErrorReply,
    Message,
    MotoReadIoBit,
    MotoReadIoBitReply,
    MotoReadIoGroup,
    MotoReadIoGroupReply,
    MotoReadMRegister,
    MotoReadMRegisterReply,
    MotoWriteIoBit,
    MotoWriteIoBitReply,
    MotoWriteIoGroup,
    MotoWriteIoGroupReply,
    MotoWriteMRegister,
    MotoWriteMRegisterReply,
    WireMessage,
)
from pymotoros.protocol.sizes import Accept, Reject, Verdict, expected_size
from pymotoros.runtime.connections import IO_CLIENTS
from pymotoros.runtime.tcp import Connection, FramedService, ServiceWiring

__all__ = ["IoServer", "handle_io_request", "log_rejection"]

logger = logging.getLogger(__name__)

_Reads = MotoReadIoBit | MotoReadIoGroup | MotoReadMRegister
_Writes = MotoWriteIoBit | MotoWriteIoGroup | MotoWriteMRegister

_ReadRow = tuple[str, Callable[[MotoRosController, int], IoRead], Callable[[int, int], Message]]
_WriteRow = tuple[
    str, Callable[[MotoRosController, int, int], IoResultCode], Callable[[int], Message]
]

_READS: Final[dict[type[_Reads], _ReadRow]] = {
    MotoReadIoBit: ("read bit", lambda c, a: c.read_io_bit(a), MotoReadIoBitReply),
    MotoReadIoGroup: ("read group", lambda c, a: c.read_io_group(a), MotoReadIoGroupReply),
    MotoReadMRegister: (
        "read M-register",
        lambda c, n: c.read_mregister(n),
        MotoReadMRegisterReply,
    ),
}
"""Each read request: its name in the refusal log, the controller's read, the reply type."""

_WRITES: Final[dict[type[_Writes], _WriteRow]] = {
    MotoWriteIoBit: ("write bit", lambda c, a, v: c.write_io_bit(a, v), MotoWriteIoBitReply),
    MotoWriteIoGroup: (
        "write group",
        lambda c, a, v: c.write_io_group(a, v),
        MotoWriteIoGroupReply,
    ),
    MotoWriteMRegister: (
        "write M-register",
        lambda c, n, v: c.write_mregister(n, v),
        MotoWriteMRegisterReply,
    ),
}
"""Each write request: its name in the refusal log, the controller's write, the reply type."""


def _log_io_refusal(
    port: str,
    what: str,
    target: int,
    code: IoResultCode,
    value: int,
    conn: Connection | None,
    log: logging.Logger,
) -> None:
    if code != IoResultCode.OK and (
        conn is None or conn.log.allow("refused IO requests", log, logging.INFO)
    ):
        log.info(
            "%s: %s %d (value %d) refused: %s",
            port,
            what,
            target,
            value,
            IoResultCode.describe(code),
        )


def log_rejection(
    conn: Connection,
    frame: Frame,
    verdict: Reject,
    order: ByteOrder,
    port: Port,
    log: logging.Logger = logger,
) -> None:
    """One warning per protocol error, with the sizes behind it (motion and IO ports);
    past the client's allowance only counted (runtime/log_limit.py). ``log``: the
    logger of the port's server, so that a user filtering by logger sees each port's
    lines, and its summaries, under that port's name."""
    if not conn.log.allow("refused frames", log, logging.WARNING):
        return
    expected = expected_size(frame.msg_type, port, frame.body, order)
    if expected is None:
        why = f"type {frame.msg_type} is not served on the {port.value} port"
    else:
        why = f"type {frame.msg_type} needs {expected} bytes, the frame has {frame.size}"
    log.warning(
        "%s: client %s: answered INVALID/%d (%s): %s",
        port.value,
        conn.peer,
        verdict.subcode,
        verdict.subcode.meaning,
        why,
    )


def handle_io_request(
    controller: MotoRosController,
    msg: WireMessage,
    port: str,
    conn: Connection | None = None,
    log: logging.Logger = logger,
) -> Message | None:
    """The reply to an IO request, or None if ``msg`` is not an IO request of this port.

    M-register requests are only IO-port messages; the motion server never passes them.
    Refusals are logged to ``log`` (the port's server's logger) within ``conn``'s
    allowance (runtime/log_limit.py) when given.
    """
    if isinstance(msg, _Reads):
        what, read_from, read_reply = _READS[type(msg)]
        read = read_from(controller, msg[0])
        _log_io_refusal(port, what, msg[0], read.result_code, 0, conn, log)
        return read_reply(read.value, int(read.result_code))
    if isinstance(msg, _Writes):
        what, write_to, write_reply = _WRITES[type(msg)]
        target, value = msg
        code = write_to(controller, target, value)
        _log_io_refusal(port, what, target, code, value, conn, log)
        return write_reply(int(code))
    return None


class IoServer(FramedService):
    """Serves IO reads and writes to one client."""

    name = "io"

    port_kind = Port.IO

    def __init__(
        self,
        controller: MotoRosController,
        order: ByteOrder,
        *,
        fidelity: Fidelity | None = None,
        **wiring: Unpack[ServiceWiring],
    ) -> None:
        """``fidelity``: exact or safe (docs/fidelity.md); None takes the controller's.
        ``wiring``: what the application gives (``runtime.tcp.ServiceWiring``)."""
        # The IO port's replacement rule tests the *motion* queues, as MotoROS does (§2.2).
        super().__init__(
            IO_CLIENTS,
            lambda: controller.has_queued_motion(),
            order,
            IoErrorReply(ResultCode.INVALID, InvalidSubcode.MSGSIZE),
            controller.fidelity if fidelity is None else fidelity,
            **wiring,
        )
        self._controller = controller
        self.requests = 0

    def on_connect(self, conn: Connection) -> None:
        self._controller.io_connected()

    def lint(self, code: LintCode, conn: Connection, detail: str = "") -> None:
        c = self._controller
        c.lint.record(code, conn.peer, c.time_ms / 1000.0, detail)

    async def serve_connection(self, conn: Connection) -> None:
        async with contextlib.aclosing(self.read_requests(conn)) as requests:
            async for frame, verdict in requests:
                await self.send(conn, self._reply(conn, frame, verdict))

    def _reply(self, conn: Connection, frame: Frame, verdict: Verdict) -> Message:
        self.requests += 1
        if isinstance(verdict, Reject):
            log_rejection(conn, frame, verdict, self._order, Port.IO)
            return verdict.reply
        reply = None
        if isinstance(verdict, Accept):
            reply = handle_io_request(self._controller, verdict.message, "io", conn)
        if reply is None:  # pragma: no cover - check_request only accepts IO types here
            return IoErrorReply(ResultCode.INVALID, InvalidSubcode.MSGTYPE)
        return reply
