"""A fault-injecting TCP proxy between a client and the twin, for the network-fault tests.

One :class:`FaultProxy` listens on 127.0.0.1 port 0 and forwards every connection it
accepts to one upstream port (a MotoROS port of the twin). What a shop-floor network
does to a cell is switched on and off while traffic flows:

* ``latency_s`` / ``jitter_s``: every chunk waits ``latency + uniform(0, jitter)`` from a
  seeded generator (order is kept: a chunk never overtakes the one before it);
* ``one_byte``: chunks are written one byte at a time, each with its own drain, so the
  peer's decoder sees every possible split of a frame;
* :meth:`stall_downstream`: bytes from the controller stop reaching the client while the
  sockets stay open (a state stream that stalls);
* :meth:`vanish`: nothing is forwarded either way and no socket is closed (a peer that
  disappears without FIN: a cable pulled, a laptop asleep);
* :meth:`reset`: every connection is closed with RST (``SO_LINGER`` 0) on both sides.

Everything that passes towards the controller is recorded per connection
(:attr:`Link.upstream_bytes`), so a test can decode what the twin actually received.
Every wait is bounded: :meth:`close` cancels the pumps and waits at most
:data:`CLOSE_TIMEOUT_S`.
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import socket
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Final

CLOSE_TIMEOUT_S: Final = 2.0
READ_CHUNK: Final = 4096


@dataclass
class Link:
    """One accepted connection and its upstream twin."""

    index: int
    client_writer: asyncio.StreamWriter
    upstream_writer: asyncio.StreamWriter
    upstream_bytes: bytearray = field(default_factory=bytearray)
    """Every byte forwarded to the controller, in order."""
    downstream_bytes: bytearray = field(default_factory=bytearray)
    """Every byte delivered to the client, in order."""
    tasks: list[asyncio.Task[None]] = field(default_factory=list)


class FaultProxy:
    """Forwards 127.0.0.1:port (chosen by the OS) to ``upstream_host:upstream_port``."""

    def __init__(
        self,
        upstream_host: str,
        upstream_port: int,
        *,
        seed: int = 0,
        latency_s: float = 0.0,
        jitter_s: float = 0.0,
        one_byte: bool = False,
    ) -> None:
        self.upstream_host = upstream_host
        self.upstream_port = upstream_port
        self.latency_s = latency_s
        self.jitter_s = jitter_s
        self.one_byte = one_byte
        self._random = random.Random(seed)
        self._server: asyncio.Server | None = None
        self.links: list[Link] = []
        self._downstream_open = asyncio.Event()
        self._downstream_open.set()
        self._vanished = False
        self._changed = asyncio.Event()
        self.port = 0
        self.loop: asyncio.AbstractEventLoop | None = None
        """The loop the proxy runs on (set by :meth:`start`)."""

    async def start(self) -> FaultProxy:
        self.loop = asyncio.get_running_loop()
        self._server = await asyncio.start_server(self._accept, "127.0.0.1", 0)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def __aenter__(self) -> FaultProxy:
        return await self.start()

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    # ------------------------------------------------------------------ faults

    def stall_downstream(self) -> None:
        """Stop delivering the controller's bytes to the client; sockets stay open."""
        self._downstream_open.clear()

    def resume_downstream(self) -> None:
        self._downstream_open.set()

    def vanish(self) -> None:
        """Stop forwarding both ways and never close a socket: no FIN, no RST."""
        self._vanished = True
        self._downstream_open.clear()

    def reset(self) -> None:
        """Close every connection with RST on both sides (a switch dropping them)."""
        for link in self.links:
            for writer in (link.client_writer, link.upstream_writer):
                _abort(writer)
            for task in link.tasks:
                task.cancel()

    # ------------------------------------------------------------------ waiting

    async def wait_until(self, predicate: Callable[[], bool], timeout_s: float = 10.0) -> None:
        """Wait (bounded) until ``predicate()`` holds; re-checked whenever bytes pass."""
        async with asyncio.timeout(timeout_s):
            while not predicate():
                event = self._changed
                await event.wait()

    def _notify(self) -> None:
        self._changed.set()
        self._changed = asyncio.Event()

    # ------------------------------------------------------------------ forwarding

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            up_reader, up_writer = await asyncio.open_connection(
                self.upstream_host, self.upstream_port
            )
        except OSError:
            _abort(writer)
            return
        for w in (writer, up_writer):
            sock = w.get_extra_info("socket")
            if sock is not None:
                with contextlib.suppress(OSError):
                    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        link = Link(len(self.links), writer, up_writer)
        self.links.append(link)
        link.tasks = [
            asyncio.create_task(self._pump(reader, up_writer, link, upstream=True)),
            asyncio.create_task(self._pump(up_reader, writer, link, upstream=False)),
        ]
        self._notify()

    async def _pump(
        self,
        reader: asyncio.StreamReader,
        writer: asyncio.StreamWriter,
        link: Link,
        *,
        upstream: bool,
    ) -> None:
        """Copy one direction with the configured delay; FIN is passed on as FIN."""
        loop = asyncio.get_running_loop()
        due = 0.0
        try:
            while True:
                data = await reader.read(READ_CHUNK)
                if not data:
                    break
                if self._vanished:
                    continue  # swallowed: the peer is gone but its socket is not
                delay = self.latency_s + (
                    self._random.uniform(0, self.jitter_s) if self.jitter_s else 0
                )
                due = max(due, loop.time() + delay)  # order kept: never before the last chunk
                if due > loop.time():
                    await asyncio.sleep(due - loop.time())
                if not upstream:
                    await self._downstream_open.wait()
                    if self._vanished:
                        continue
                (link.upstream_bytes if upstream else link.downstream_bytes).extend(data)
                if self.one_byte:
                    for i in range(len(data)):
                        writer.write(data[i : i + 1])
                        await writer.drain()
                else:
                    writer.write(data)
                    await writer.drain()
                self._notify()
            if not self._vanished and writer.can_write_eof():
                writer.write_eof()
        except (OSError, asyncio.IncompleteReadError):
            _abort(writer)
        finally:
            self._notify()

    async def close(self) -> None:
        """Stop listening, end every pump and close every socket (bounded)."""
        if self._server is not None:
            self._server.close()
        tasks = [t for link in self.links for t in link.tasks]
        for task in tasks:
            task.cancel()
        for link in self.links:
            for w in (link.client_writer, link.upstream_writer):
                w.close()
        if tasks:
            await asyncio.wait(tasks, timeout=CLOSE_TIMEOUT_S)
        if self._server is not None:
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(CLOSE_TIMEOUT_S):
                    await self._server.wait_closed()


def _abort(writer: asyncio.StreamWriter) -> None:
    """Close with RST: SO_LINGER on, timeout 0, then close."""
    sock = writer.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    transport = writer.transport
    transport.abort()
