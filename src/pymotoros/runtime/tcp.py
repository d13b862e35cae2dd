"""What the three MotoROS servers share: listening, admission, one task per client, closing.

A :class:`TcpService` listens on a pre-bound socket (so port 0 works and the real
port is known before anyone connects), applies the §2.2 admission rule through a
:class:`~pymotoros.runtime.connections.SlotTable`, sets TCP_NODELAY and
SO_KEEPALIVE, and runs each client in a named task of the application's
``TaskGroup``. A crash in one client's handler is logged and closes that connection
only; cancellation always propagates.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import socket
import struct
from abc import ABC, abstractmethod
from collections.abc import AsyncGenerator, Callable
from typing import Final, TypedDict, Unpack

from pymotoros.capture import Flow, SessionRecorder
from pymotoros.controller.lint import LintCode
from pymotoros.errors import RemoteProtocolError
from pymotoros.models.fidelity import DEFAULT_FIDELITY, Fidelity
from pymotoros.protocol.constants import ByteOrder, Port
from pymotoros.protocol.framing import Frame, FrameDecoder, encode
from pymotoros.protocol.messages import Message
from pymotoros.protocol.receiver import MotoRosReceiver, turn_verdict
from pymotoros.protocol.sizes import (
    Accept,
    Verdict,
    check_request,
    expected_size,
    is_length_mismatch,
)
from pymotoros.runtime.connections import (
    AdmissionKind,
    SlotTable,
    configure_socket,
    peer_name,
)
from pymotoros.runtime.log_limit import LogLimiter, loop_later, loop_time
from pymotoros.runtime.traffic import Traffic

__all__ = [
    "ClientTasks",
    "Connection",
    "FramedService",
    "ServiceWiring",
    "TcpService",
    "bind_socket",
    "is_loopback",
]

logger = logging.getLogger(__name__)

CLOSE_TIMEOUT_S: Final = 1.0
"""How long closing a client may wait for its transport to finish."""

READ_CHUNK: Final = 4096
"""Bytes asked of the socket per read in fidelity safe (MotoROS reads at most 552, as
fidelity exact does: ``protocol.receiver.RECV_SIZE``)."""


def is_loopback(host: str) -> bool:
    """True if ``host`` names only loopback addresses (``localhost`` included)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def bind_socket(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (port 0: the OS chooses)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.create_server((host, port), family=family, backlog=socket.SOMAXCONN)
    sock.setblocking(False)
    return sock


def bind_unlistened(host: str, port: int) -> socket.socket:
    """A TCP socket bound to ``host:port`` but not listening: connections are refused
    until a server starts on it (MotoROS before its start-up checks pass)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        if hasattr(socket, "SO_REUSEADDR"):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
    except BaseException:
        sock.close()
        raise
    sock.setblocking(False)
    return sock


def _peer_port(writer: asyncio.StreamWriter) -> int | None:
    """The client's TCP port, None for an in-memory client (the recorder makes one up)."""
    peer = writer.get_extra_info("peername")
    return int(peer[1]) if isinstance(peer, tuple) and len(peer) >= 2 else None


class Connection:
    """One accepted client.

    Servers read and write through :meth:`read` and :meth:`write`: the one place
    that records the connection when ``pymotoros sim --record`` is on (``flow``).
    """

    __slots__ = ("flow", "log", "logged", "peer", "reader", "writer")

    def __init__(
        self,
        reader: asyncio.StreamReader,
        writer: asyncio.StreamWriter,
        service: str = "tcp",
        now: Callable[[], float] = loop_time,
    ) -> None:
        self.reader = reader
        self.writer = writer
        self.peer = peer_name(writer)
        self.flow: Flow | None = None
        """This connection in the session recording, if one is being made."""
        self.log = LogLimiter(f"{service}: client {self.peer}", now, schedule=loop_later)
        """Bounds the lines this client makes the server log (runtime/log_limit.py)."""
        self.logged = True
        """Whether this connection's life cycle (connected, lost, disconnected) is
        logged: False once the port's connection lines are being only counted."""

    async def read(self, n: int) -> bytes:
        """Up to ``n`` bytes from the client (b"" at EOF), recorded."""
        data = await self.reader.read(n)
        if self.flow is not None:
            if data:
                self.flow.from_client(data)
            else:
                self.flow.closed()
                self.flow = None
        return data

    def write(self, data: bytes) -> None:
        """Queue ``data`` for the client, recorded; the caller drains."""
        if self.flow is not None:
            self.flow.to_client(data)
        self.writer.write(data)

    def close(self) -> None:
        """Close the transport; a handler blocked on it wakes with EOF."""
        if self.flow is not None:
            self.flow.server_closed()
            self.flow = None
        if not self.writer.is_closing():
            self.writer.close()


class ClientTasks(dict[Connection, "asyncio.Task[None]"]):
    """One port's open connections and their tasks: the server keeps them here, and
    whoever was given the same object may cut them all at once.

    Made before the controller, so that the motion port's can be given both to the
    controller (its :class:`~pymotoros.controller.ports.MotionLink`, for a scenario's
    ``drop_motion``) and to the :class:`~pymotoros.runtime.motion_server.MotionServer`
    at their construction: neither is plugged into the other afterwards.
    """

    __slots__ = ()

    def drop_clients(self) -> None:
        """Close every client's connection now, as a cable pulled (fault injection)."""
        for conn in list(self):
            conn.close()


class ServiceWiring(TypedDict, total=False):
    """What a server is given by the application that runs it, at construction."""

    clients: ClientTasks
    """Where the server keeps its connections (default: its own)."""
    catch_up: Callable[[], object] | None
    """Called first on every accept: brings a batching ticker up to date (issue 13)."""
    log_clock: Callable[[], float]
    """The clock of the log limiters (the application's clock when it has one)."""
    recorder: SessionRecorder | None
    """Records every accepted connection (``pymotoros sim --record``)."""


class TcpService(ABC):
    """One MotoROS server port."""

    name: str = "tcp"

    def __init__(
        self,
        capacity: int,
        motion_queued: Callable[[], bool],
        *,
        clients: ClientTasks | None = None,
        catch_up: Callable[[], object] | None = None,
        log_clock: Callable[[], float] = loop_time,
        recorder: SessionRecorder | None = None,
    ) -> None:
        """The keyword arguments are :class:`ServiceWiring`'s."""
        self._slots: SlotTable[Connection] = SlotTable(capacity)
        self._motion_queued = motion_queued
        self._server: asyncio.Server | None = None
        self._tg: asyncio.TaskGroup | None = None
        self._tasks: ClientTasks = clients if clients is not None else ClientTasks()
        self.port: int = 0
        self.accepted = 0
        self.refused = 0
        self.replaced = 0
        self._recorder = recorder
        self._catch_up = catch_up
        self.log_clock = log_clock
        """The clock of the log limiters (a test may swap it for a fake one)."""
        self.log = LogLimiter(self.name, lambda: self.log_clock(), schedule=loop_later)
        """Bounds the connection lines a flood of connects makes this port log."""

    # ----------------------------------------------------------- life cycle

    async def start(self, tg: asyncio.TaskGroup, sock: socket.socket) -> int:
        """Start accepting on the bound ``sock`` (it is the server's from now on); client
        tasks will live in ``tg``. Returns the port."""
        self._tg = tg
        self.port = int(sock.getsockname()[1])
        self._server = await asyncio.start_server(self._accept, sock=sock)
        logger.info("%s server listening on port %d", self.name, self.port)
        return self.port

    def attach(self, tg: asyncio.TaskGroup) -> None:
        """Serve clients handed over by :meth:`accept` without listening on a socket.

        The in-memory twin (``pymotoros.testing``) connects its clients this way; the
        admission rules and the handlers are the same as for TCP clients.
        """
        self._tg = tg

    def accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        """Take one client's byte streams, as if it had just connected over TCP."""
        self._accept(reader, writer)

    def stop_accepting(self) -> None:
        if self._server is not None:
            self._server.close()

    def drop_clients(self) -> None:
        """Close every client's connection now, as a cable pulled (fault injection)."""
        self._tasks.drop_clients()

    async def close_clients(self) -> None:
        """Close every client and wait for its task to finish."""
        tasks = list(self._tasks.values())
        for conn in list(self._tasks):
            conn.close()
        for task in tasks:
            task.cancel()
        if tasks:
            await asyncio.wait(tasks, timeout=CLOSE_TIMEOUT_S)

    async def wait_closed(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None
        self.log.close()  # the totals of connection lines a flood left unlogged

    @property
    def clients(self) -> int:
        return len(self._slots)

    # ----------------------------------------------------------- accepting

    def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if self._catch_up is not None:
            self._catch_up()
        conn = Connection(reader, writer, self.name, self.log_clock)
        tg = self._tg
        if tg is None:  # pragma: no cover - start() sets it before accepting
            writer.close()
            return
        queued = self._motion_queued()
        admission = self._slots.admit(conn, queued)
        if admission.kind is AdmissionKind.REFUSE:
            self.refused += 1
            if self.log.allow("refused connections", logger, logging.WARNING):
                logger.warning(
                    "%s: refused %s: all %d connection slots are taken and motion is queued "
                    "(MotoROS closes the newcomer while the robot moves)",
                    self.name,
                    conn.peer,
                    self._slots.capacity,
                )
            writer.close()
            return
        if admission.kind is AdmissionKind.REPLACE and admission.evicted is not None:
            self.replaced += 1
            if self.log.allow("replaced connections", logger, logging.WARNING):
                logger.warning(
                    "%s: %s replaces %s in slot 0 (all %d slots taken, no motion queued)",
                    self.name,
                    conn.peer,
                    admission.evicted.peer,
                    self._slots.capacity,
                )
            self._evict(admission.evicted)
            # MotoROS closes the old connection and deletes its tasks before the new one
            # takes the slot (§2.2): its disconnect now, as its own close no longer frees
            # a slot (the pending point is dropped; the new client starts the tasks again)
            self._disconnected(admission.evicted)
        self.accepted += 1
        configure_socket(writer)
        if self._recorder is not None:
            conn.flow = self._recorder.flow(self.port, _peer_port(writer))
        coro = self._run(conn)
        try:
            task = tg.create_task(coro, name=f"{self.name}:{conn.peer}")
        except RuntimeError:  # accepted while the task group shuts down
            coro.close()
            self._slots.release(conn)
            writer.close()
            return
        self._tasks[conn] = task

    def _evict(self, conn: Connection) -> None:
        conn.close()
        task = self._tasks.get(conn)
        if task is not None:
            task.cancel()

    async def _run(self, conn: Connection) -> None:
        conn.logged = self.log.allow("connections", logger, logging.INFO)
        if conn.logged:
            logger.info(
                "%s: client %s connected (%d/%d)",
                self.name,
                conn.peer,
                len(self._slots),
                self._slots.capacity,
            )
        try:
            self.on_connect(conn)
            await self.serve_connection(conn)
        except (OSError, asyncio.IncompleteReadError) as exc:  # resets, keep-alive timeouts
            if conn.logged:
                logger.info("%s: client %s: connection lost (%s)", self.name, conn.peer, exc)
        except Exception:
            if self.log.allow("failed handlers", logger, logging.ERROR):
                logger.exception("%s: client %s: handler failed; closing it", self.name, conn.peer)
        finally:
            self._tasks.pop(conn, None)
            # on_disconnect before any await: once the slot is free a new client may
            # connect and start its tasks, which a late on_disconnect would end (§2.2)
            if self._slots.release(conn):
                self._disconnected(conn)
            conn.close()
            with contextlib.suppress(Exception, asyncio.CancelledError):
                async with asyncio.timeout(CLOSE_TIMEOUT_S):
                    await conn.writer.wait_closed()
            if conn.logged:
                logger.info("%s: client %s disconnected", self.name, conn.peer)
            conn.log.close()  # the totals of what this client's flood left unlogged

    def _disconnected(self, conn: Connection) -> None:
        try:
            self.on_disconnect(conn)
        except Exception:
            logger.exception("%s: client %s: disconnect handling failed", self.name, conn.peer)

    # ----------------------------------------------------------- hooks

    def on_connect(self, conn: Connection) -> None:  # noqa: B027 - optional hook
        """Called when a client has taken its slot."""

    def on_disconnect(self, conn: Connection) -> None:  # noqa: B027 - optional hook
        """Called when a client that held a slot is gone."""

    @abstractmethod
    async def serve_connection(self, conn: Connection) -> None:
        """Serve one client until EOF; return to close it."""


class FramedService(TcpService):
    """A port that reads Simple Message requests and answers each with one write.

    Shared by the motion and IO servers. How requests are cut from the byte stream
    depends on the fidelity (docs/fidelity.md §1):

    - exact: as MotoROS 1.9.12 (:mod:`pymotoros.protocol.receiver`): reads of at most
      552 bytes, sizes from the type, the prefix never read, a message split across
      reads answered 3001 and its tail read as a new message;
    - safe: frames are cut by their length prefix and reassembled across reads; a
      prefix outside the legal range is answered INVALID/3001 with the port's own
      error reply, after which the buffered bytes are dropped to resynchronise.

    The decisions a client lint reports are each made in one method:
    :meth:`fragment_seen`, :meth:`length_mismatch_seen`.
    """

    port_kind: Port = Port.MOTION
    """Which size table the port's requests follow (§1.5)."""

    def __init__(
        self,
        capacity: int,
        motion_queued: Callable[[], bool],
        order: ByteOrder,
        bad_prefix_reply: Message,
        fidelity: Fidelity = DEFAULT_FIDELITY,
        **wiring: Unpack[ServiceWiring],
    ) -> None:
        super().__init__(capacity, motion_queued, **wiring)
        self._order = order
        self._bad_prefix_reply = bad_prefix_reply
        self.fidelity = fidelity
        """exact or safe (docs/fidelity.md): fixed for the server's life."""
        self.traffic = Traffic()
        """Requests and replies counted for ``GET /metrics`` (plain ints, runtime/traffic.py)."""
        # Log as the concrete server's module (pymotoros.runtime.motion_server …), so that
        # a user filtering by logger sees its protocol events where they belong.
        self._log = logging.getLogger(type(self).__module__)

    async def read_requests(self, conn: Connection) -> AsyncGenerator[tuple[Frame, Verdict], None]:
        """Each request ``conn`` sends, with what MotoROS does with it, until EOF."""
        if self.fidelity is Fidelity.EXACT:
            async with contextlib.aclosing(self._exact_requests(conn)) as turns:
                async for item in turns:
                    yield item
            return
        async with contextlib.aclosing(self.frames(conn)) as frames:
            async for frame in frames:
                verdict = check_request(frame, self._order, self.port_kind)
                if is_length_mismatch(frame, verdict):
                    kind, order = self.port_kind, self._order
                    expected = (
                        frame.size - verdict.surplus
                        if isinstance(verdict, Accept)
                        else expected_size(frame.msg_type, kind, frame.body, order)
                    )
                    self.length_mismatch_seen(conn, frame.msg_type, frame.size, expected)
                yield frame, verdict

    async def _exact_requests(
        self, conn: Connection
    ) -> AsyncGenerator[tuple[Frame, Verdict], None]:
        """MotoROS's receive loop (fidelity exact): one pass per reply."""
        receiver = MotoRosReceiver(self._order, self.port_kind)
        while True:
            if receiver.wants_read:
                data = await conn.read(receiver.read_size)
                if not data:
                    return
                receiver.feed(data)
            turn = receiver.turn()
            # A short message whose prefix counts exactly the bytes that came is whole,
            # only shorter than its type: MotoROS answers it 3001 as any cut message
            # (the reply comes from turn_verdict, unchanged), but the lint names it a
            # length mismatch, not a fragment: no tail follows it.
            short = turn.cut and turn.prefix is not None and turn.prefix + 4 == turn.received
            if (turn.cut or turn.joined) and not short:
                self.fragment_seen(conn, turn.frame.msg_type, turn.received, turn.expected)
            if (turn.length_mismatch or short) and turn.prefix is not None:
                self.length_mismatch_seen(conn, turn.frame.msg_type, turn.prefix + 4, turn.expected)
            self.traffic.request(turn.frame.msg_type)
            yield turn.frame, turn_verdict(turn, self._order, self.port_kind)

    def fragment_seen(
        self, conn: Connection, msg_type: int, received: int, expected: int | None
    ) -> None:
        """A request arrived in more than one read (the one place this is decided).

        exact: ``received`` bytes were answered 3001 (``expected`` is the type's size,
        None under 16 bytes) or, joined with kept bytes, processed; safe: reassembled.
        """
        self.lint(LintCode.FRAGMENTED_MESSAGE, conn, f"type {msg_type}")
        self._log.debug(
            "%s: client %s: type %d arrived in more than one read (%d of %s bytes in one); %s",
            self.name,
            conn.peer,
            msg_type,
            received,
            "?" if expected is None else expected,
            "answered 3001 as MotoROS does"
            if self.fidelity is Fidelity.EXACT
            else "reassembled (a real controller would answer 3001)",
        )

    def length_mismatch_seen(
        self, conn: Connection, msg_type: int, by_prefix: int, expected: int | None
    ) -> None:
        """A request whose length prefix says ``by_prefix`` bytes in all while its type
        needs ``expected`` (the one place this is decided). MotoROS never reads the
        prefix (§1.1); the safe setting frames by it."""
        needs = "?" if expected is None else expected - 4
        self.lint(
            LintCode.LENGTH_MISMATCH,
            conn,
            f"type {msg_type}: prefix length {by_prefix - 4}, the type needs {needs}",
        )
        self._log.debug(
            "%s: client %s: type %d: the prefix says %d bytes, the type needs %s",
            self.name,
            conn.peer,
            msg_type,
            by_prefix,
            "?" if expected is None else expected,
        )

    async def frames(self, conn: Connection) -> AsyncGenerator[Frame, None]:
        """The whole frames ``conn`` sends, cut by their length prefix, until EOF (safe)."""
        decoder = FrameDecoder(self._order)
        while data := await conn.read(READ_CHUNK):
            fragmented = decoder.buffered > 0
            decoder.feed(data)
            while True:
                try:
                    frame = decoder.next_frame()
                except RemoteProtocolError as exc:
                    dropped = decoder.discard()
                    if conn.log.allow("refused frames", self._log, logging.WARNING):
                        self._log.warning(
                            "%s: client %s: %s; %d bytes dropped, answered INVALID/3001",
                            self.name,
                            conn.peer,
                            exc,
                            len(dropped),
                        )
                    self._bad_prefix_seen(conn, dropped)
                    await self.send(conn, self._bad_prefix_reply)
                    break
                if frame is None:
                    break
                if fragmented:
                    fragmented = False
                    self.fragment_seen(conn, frame.msg_type, len(data), frame.size)
                self.traffic.request(frame.msg_type)
                yield frame

    def _bad_prefix_seen(self, conn: Connection, dropped: bytes) -> None:
        """A prefix outside 12..548 (safe refuses it): a length mismatch, as exact finds
        the same bytes (its reads never look at the prefix)."""
        if len(dropped) < 8:
            return  # not even a type: nothing to name
        prefix, msg_type = struct.unpack(self._order.value + "ii", dropped[:8])
        expected = expected_size(msg_type, self.port_kind, dropped[16:], self._order)
        self.length_mismatch_seen(conn, msg_type, prefix + 4, expected)

    def lint(self, code: LintCode, conn: Connection, detail: str = "") -> None:
        """Hook: a client lint finding on ``conn`` (issue 31); the motion and IO servers
        record it on their controller, in controller time."""

    async def send(self, conn: Connection, message: Message) -> None:
        """One write per message: common clients read one reply per ``recv()`` (clients §1.3)."""
        self.traffic.reply(message)
        conn.write(encode(message, self._order))
        await conn.writer.drain()
