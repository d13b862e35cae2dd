"""One TCP connection speaking Simple Message, over asyncio streams.

A reader task feeds a :class:`FrameDecoder` and hands each decoded message either
to the request waiting for it (motion and IO ports: strict request/reply, one
request in flight behind a lock, the echo checked) or to a topic callback (state
port). When the socket closes or breaks, the reader fails the waiting request and
every later one with :class:`ConnectionLostError` at once, and sets :attr:`closed`.

Every wait has a timeout (``asyncio.timeout``).
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import socket
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Final, TypeAlias

from pymotoros.client.errors import (
    REPLACED_MOTION_CLIENT,
    SECOND_MOTION_CLIENT,
    ConnectError,
    ConnectionLostError,
    RequestTimeoutError,
)
from pymotoros.client.recorder import active_flow
from pymotoros.errors import RemoteProtocolError
from pymotoros.protocol.constants import (
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    TCP_PORT_STATE,
    ByteOrder,
    CommType,
    MotionCommand,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import FrameDecoder, decode_reply, encode, prefix_fits
from pymotoros.protocol.messages import (
    IoErrorReply,
    Message,
    MotoMotionCtrl,
    MotoMotionReply,
    UnknownMessage,
    WireMessage,
)

logger = logging.getLogger(__name__)
wire_logger = logging.getLogger("pymotoros.client.wire")
request_logger = logging.getLogger("pymotoros.client.requests")
"""One line per request and per reply (``pymotoros -v``); the wire bytes are at DEBUG."""

READ_CHUNK: Final = 4096
DEFAULT_CONNECT_TIMEOUT_S: Final = 5.0
DEFAULT_REQUEST_TIMEOUT_S: Final = 5.0
CLOSE_TIMEOUT_S: Final = 2.0

MAX_ORPHANS: Final = 8
"""Requests sent whose waiter gave up (cancelled or timed out) and whose reply may still
come: their replies are recognised and discarded, not logged as unexpected. A peer
answers in order, so a handful covers every real case (a cancel mid-request, a timeout)."""

Connector: TypeAlias = Callable[
    [str, int], Awaitable[tuple[asyncio.StreamReader, asyncio.StreamWriter]]
]
"""Opens the byte stream to ``host:port``; the default is ``asyncio.open_connection`` (TCP).
The in-memory twin (:mod:`pymotoros.testing`) passes its own."""

_TOPIC: Final = int(CommType.TOPIC)
"""A plain int: compared with every received frame's comm type."""

_PORT_HINT: Final[dict[Port, str]] = {
    Port.MOTION: "--motion-port",
    Port.STATE: "--state-port",
    Port.IO: "--io-port",
}


@dataclass(frozen=True, slots=True)
class Ports:
    """The three MotoROS TCP ports (defaults: 50240, 50241, 50242)."""

    motion: int = TCP_PORT_MOTION
    state: int = TCP_PORT_STATE
    io: int = TCP_PORT_IO

    def of(self, kind: Port) -> int:
        """The port number for one of the three kinds (motion, state or IO)."""
        return {Port.MOTION: self.motion, Port.STATE: self.state, Port.IO: self.io}[kind]


def expected_echo(request: WireMessage) -> tuple[int, int] | None:
    """(command, sequence) a MOTO_MOTION_REPLY must echo for ``request`` (§1.6), if any.

    Derived from the message's own layout (``Message.reply_echo``), so a new request
    type needs no entry here.
    """
    return request.reply_echo() if isinstance(request, Message) else None


def reply_matches(request: WireMessage, reply: WireMessage, expected: type | None) -> bool:
    """Is ``reply`` the answer to ``request``?

    A MOTION_REPLY must echo the command and sequence. A request the controller
    does not know is answered with a MOTION_REPLY echoing its message type with
    sequence -1 (3003), on the IO port with the IO error reply (§1.6).
    """
    if isinstance(reply, MotoMotionReply):
        echo = expected_echo(request)
        if echo is not None:
            return (reply.command, reply.sequence) == echo
        req_type = request.msg_type if isinstance(request, UnknownMessage) else request.MSG_TYPE
        return reply.command == req_type
    if isinstance(reply, IoErrorReply):
        return True
    return expected is not None and isinstance(reply, expected)


def _order_hint(data: bytes, order: ByteOrder) -> str:
    """A hint when the bytes would make sense in the other byte order."""
    other = ByteOrder.BIG if order is ByteOrder.LITTLE else ByteOrder.LITTLE
    if prefix_fits(data, other):
        return (
            "; the bytes read well in the other byte order: check --controller "
            "(the FS100 is big-endian, every other controller little-endian)"
        )
    return ""


class FrameConnection:
    """A Simple Message connection to one MotoROS port."""

    def __init__(
        self,
        reader: asyncio.StreamReader,
        writer: asyncio.StreamWriter,
        *,
        kind: Port,
        host: str,
        port: int,
        order: ByteOrder,
        on_topic: Callable[[WireMessage], None] | None = None,
        on_lost: Callable[[ConnectionLostError], None] | None = None,
    ) -> None:
        self.kind = kind
        self.host = host
        self.port = port
        self.order = order
        self._reader = reader
        self._writer = writer
        self._decoder = FrameDecoder(order)
        self._on_topic = on_topic
        self._on_lost = on_lost
        self._lock = asyncio.Lock()
        self._pending: tuple[asyncio.Future[WireMessage], WireMessage, type | None] | None = None
        self._orphans: collections.deque[tuple[WireMessage, type | None]] = collections.deque(
            maxlen=MAX_ORPHANS
        )
        """Requests sent and given up on (cancel, timeout): their replies are still owed."""
        self._error: ConnectionLostError | None = None
        self._answered = False
        """A reply has arrived on this connection (a motion port closed before any was
        closed by MotoROS's one-motion-client rule)."""
        self._closing = False
        self.closed = asyncio.Event()
        """Set once the connection is gone, for whatever reason."""
        self._flow = active_flow(port)  # the session recorder, when one is active
        self._flow_closed = False
        self._task = asyncio.create_task(self._read_loop(), name=f"pymotoros-client-{self}")

    def __str__(self) -> str:
        return f"{self.kind.value} connection to {self.host}:{self.port}"

    @classmethod
    async def open(
        cls,
        host: str,
        port: int,
        kind: Port,
        order: ByteOrder,
        *,
        timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
        on_topic: Callable[[WireMessage], None] | None = None,
        on_lost: Callable[[ConnectionLostError], None] | None = None,
        connector: Connector | None = None,
    ) -> FrameConnection:
        """Connect, or raise :class:`ConnectError` naming host:port and what to check."""
        what = f"the MotoROS {kind.value} port {host}:{port}"
        open_stream = connector or asyncio.open_connection
        try:
            async with asyncio.timeout(timeout_s):
                reader, writer = await open_stream(host, port)
        except TimeoutError:
            raise ConnectError(
                f"cannot connect to {what}: no answer within {timeout_s:g} s; check the "
                "controller's IP address and the network (ping it)",
                host=host,
                port=port,
            ) from None
        except ConnectionRefusedError:
            raise ConnectError(
                f"cannot connect to {what}: connection refused; check that MotoROS is "
                f"running (OT#891 INIT_DONE on the pendant), the host, and "
                f"{_PORT_HINT[kind]}",
                host=host,
                port=port,
            ) from None
        except OSError as exc:
            raise ConnectError(
                f"cannot connect to {what}: {exc.strerror or exc}; check the host and network",
                host=host,
                port=port,
            ) from exc
        sock = writer.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        logger.debug("connected to %s", what)
        return cls(
            reader,
            writer,
            kind=kind,
            host=host,
            port=port,
            order=order,
            on_topic=on_topic,
            on_lost=on_lost,
        )

    @property
    def error(self) -> ConnectionLostError | None:
        """Why the connection is gone, or None while it is up."""
        return self._error

    def _lost(self, reason: str) -> ConnectionLostError:
        return ConnectionLostError(f"{self} lost: {reason}")

    async def _read_loop(self) -> None:
        reason = "closed by the controller"
        decoder = self._decoder
        kind = self.kind
        try:
            while True:
                data = await self._reader.read(READ_CHUNK)
                if not data:
                    break
                if self._flow is not None:
                    self._flow.received(data)
                decoder.feed(data)
                if wire_logger.isEnabledFor(logging.DEBUG):
                    self._decode_logged()
                    continue
                # The hot path (every state message): decode straight from the buffer, no
                # Frame and no body copy; the same messages and errors as the logged path.
                while (message := decoder.next_reply(kind)) is not None:
                    if decoder.comm_type == _TOPIC:
                        if self._on_topic is not None:
                            self._on_topic(message)
                    else:
                        self._deliver(message)
        except asyncio.CancelledError:
            reason = "closed by the client"
            raise
        except RemoteProtocolError as exc:
            hint = _order_hint(exc.data, self.order)
            reason = f"undecodable data from the controller ({exc}){hint}"
            logger.error("%s: %s; data %s", self, exc, exc.data[:64].hex())
        except ConnectionResetError as exc:
            reason = f"socket error ({exc.strerror or exc})"
            if kind is Port.MOTION and not self._answered and not self._closing:
                # A controller that closes a newcomer with our request unread resets the
                # socket rather than closing it: the same one-client rule as a plain close.
                reason = f"{SECOND_MOTION_CLIENT} (the socket was reset)"
        except OSError as exc:
            reason = f"socket error ({exc.strerror or exc})"
        except Exception as exc:  # the connection boundary: fail the waiters, never leak
            reason = f"internal error ({exc!r})"
            logger.exception("%s: reader failed", self)
        finally:
            if self._closing:
                reason = "closed by the client"
            elif reason == "closed by the controller" and kind is Port.MOTION:
                reason = REPLACED_MOTION_CLIENT if self._answered else SECOND_MOTION_CLIENT
            self._fail(self._lost(reason))

    def _decode_logged(self) -> None:
        """Every buffered frame, each logged with its bytes before it is decoded."""
        while (frame := self._decoder.next_frame()) is not None:
            wire_logger.debug("%s <- type %d %s", self, frame.msg_type, frame.body.hex())
            message = decode_reply(frame, self.order, self.kind)
            if frame.comm_type == _TOPIC:
                if self._on_topic is not None:
                    self._on_topic(message)
            else:
                self._deliver(message)

    def _deliver(self, message: WireMessage) -> None:
        pending = self._pending
        if self._orphans and self._orphan_reply(message, pending):
            return
        if pending is None or pending[0].done():
            logger.warning("%s: unexpected reply %r dropped", self, message)
            return
        future, request, expected = pending
        if reply_matches(request, message, expected):
            self._answered = True
            future.set_result(message)
        else:
            logger.warning("%s: reply %r does not answer %r; dropped", self, message, request)

    def _orphan_reply(
        self,
        message: WireMessage,
        pending: tuple[asyncio.Future[WireMessage], WireMessage, type | None] | None,
    ) -> bool:
        """Is ``message`` the late reply to a request its waiter gave up on? (discarded)

        The controller answers in order, so the oldest orphan is tried first; a reply to
        the pending request instead means the orphans before it will never be answered.
        """
        orphan, expected = self._orphans[0]
        if reply_matches(orphan, message, expected):
            self._orphans.popleft()
            logger.debug("%s: late reply %r to a request given up on, discarded", self, message)
            return True
        if pending is not None and reply_matches(pending[1], message, pending[2]):
            self._orphans.clear()
        return False

    def _fail(self, error: ConnectionLostError) -> None:
        if self._error is not None:
            return
        self._error = error
        waiting = self._pending is not None and not self._pending[0].done()
        if self._pending is not None and waiting:
            self._pending[0].set_exception(error)
        self.closed.set()
        if not self._closing:
            # A request waiting for its reply fails with these very words, and its caller
            # says them (the CLI's error line): the warning is for a loss nobody waits on.
            logger.log(logging.INFO if waiting else logging.WARNING, "%s", error)
        if self._on_lost is not None:
            self._on_lost(error)

    async def request(
        self, message: WireMessage, expected: type | None, *, timeout_s: float
    ) -> WireMessage:
        """Send ``message`` and return its reply (a ``expected`` instance, or an error reply).

        One request is in flight at a time; others wait for the lock (within the
        same timeout).
        """
        try:
            async with asyncio.timeout(timeout_s):
                async with self._lock:
                    if self._error is not None:
                        raise ConnectionLostError(str(self._error))
                    future: asyncio.Future[WireMessage] = asyncio.get_running_loop().create_future()
                    self._pending = (future, message, expected)
                    sent = False
                    try:
                        data = encode(message, self.order)
                        if wire_logger.isEnabledFor(logging.DEBUG):
                            wire_logger.debug("%s -> %s", self, data.hex())
                        if request_logger.isEnabledFor(logging.INFO):
                            request_logger.info("%s -> %r", self, message)
                        self._writer.write(data)
                        sent = True
                        if self._flow is not None:
                            self._flow.sent(data)
                        await self._writer.drain()
                        reply = await future
                        if request_logger.isEnabledFor(logging.INFO):
                            request_logger.info("%s <- %r", self, reply)
                        return reply
                    except ConnectionLostError:
                        raise
                    except OSError as exc:
                        self._fail(self._lost(f"send failed ({exc})"))
                        raise ConnectionLostError(str(self._error)) from exc
                    finally:
                        self._pending = None
                        if sent and (not future.done() or future.cancelled()):
                            # cancelled or timed out (the task's cancel cancels the future
                            # it awaits): the reply is still owed, and will be recognised
                            self._orphans.append((message, expected))
                        if not future.done():
                            future.cancel()
                        elif not future.cancelled():
                            future.exception()  # failed while sending: raised above, retrieved
        except TimeoutError:
            raise RequestTimeoutError(
                f"no reply to {type(message).__name__} from {self} within {timeout_s:g} s"
            ) from None

    async def close(self) -> None:
        """Close the socket and wait for the reader to finish. Idempotent."""
        self._closing = True
        if not self._task.done():
            self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        self._fail(self._lost("closed by the client"))
        if self._flow is not None and not self._flow_closed:
            self._flow_closed = True
            self._flow.closed()  # the recording shows the client's FIN
        self._writer.close()
        with contextlib.suppress(OSError, TimeoutError):
            async with asyncio.timeout(CLOSE_TIMEOUT_S):
                await self._writer.wait_closed()


async def stop_queued_motion(conn: FrameConnection, *, timeout_s: float) -> None:
    """STOP_MOTION on a motion connection that has just opened (docs/client.md).

    MotoROS 1.9.12 keeps the increment queues when a motion connection closes, and the
    next connection, whoever opens it, re-creates the task that executes them: the
    robot resumes the old motion the moment we connect (reference §2.2). Stopping at
    once is the only way a client can keep a lost trajectory's remainder from running
    under it; the planner then waits for rest before reading the start from feedback.
    On a controller with nothing queued the request only answers SUCCESS.
    """
    request = MotoMotionCtrl(0, 0, MotionCommand.STOP_MOTION)
    reply = await conn.request(request, MotoMotionReply, timeout_s=timeout_s)
    if not isinstance(reply, MotoMotionReply) or reply.result != ResultCode.SUCCESS:
        # 2/0: a queue lock failed or the interpolators were slow; MotoROS cleared the
        # queues anyway (§3.1). Anything else is a controller we do not know.
        logger.warning(
            "%s: STOP_MOTION on connecting answered %r; the queues of a closed "
            "connection may still run: check that the robot is at rest",
            conn,
            reply,
        )
