"""A deadline on reading each HTTP request: half-sent and slow requests are closed.

uvicorn closes an idle keep-alive connection after ``timeout_keep_alive``, but a
connection that has sent *part* of a request (a header line, then nothing; a body one
byte a minute) is waited for as long as the client likes: a few hundred such sockets
(a "slowloris") hold the twin's connections and its memory. :class:`BoundedH11Protocol`
is uvicorn's h11 protocol with one more timer: from a connection's first moment, and
from the first byte of each further request, the whole request (headers and body) must
arrive within :data:`REQUEST_READ_TIMEOUT_S`, else the connection is closed. The timer
stops once the request is complete (the application's answer may take its time) and
when the connection becomes a WebSocket (the pendant's feed lives for hours).

The h11 protocol is named explicitly (not uvicorn's "auto", which takes httptools when
it is installed) so that the deadline holds whatever else is installed.
"""

from __future__ import annotations

import asyncio
from typing import Final

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

__all__ = ["REQUEST_READ_TIMEOUT_S", "BoundedH11Protocol"]

REQUEST_READ_TIMEOUT_S: Final = 10.0
"""Seconds a client has to send a whole request (the largest the control API takes,
MAX_BODY_BYTES = 256 KiB in runtime/body_limit.py, takes well under a second on any link
the twin is used over)."""


class BoundedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol, closing a connection whose request is not complete within
    ``request_timeout`` seconds (the class attribute; :func:`bounded` makes a subclass
    with another bound)."""

    request_timeout: float = REQUEST_READ_TIMEOUT_S
    _read_deadline: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def data_received(self, data: bytes) -> None:
        if self._read_deadline is None and self._between_requests():
            self._arm()  # the first byte of the next request on a kept-alive connection
        super().data_received(data)
        if self._request_complete():
            self._disarm()

    def handle_websocket_upgrade(self, event: h11.Request) -> None:
        self._disarm()
        super().handle_websocket_upgrade(event)

    def _between_requests(self) -> bool:
        return self.cycle is None or self.cycle.response_complete

    def _request_complete(self) -> bool:
        cycle = self.cycle
        return cycle is not None and not cycle.response_complete and not cycle.more_body

    def _arm(self) -> None:
        self._disarm()
        self._read_deadline = self.loop.call_later(self.request_timeout, self._too_slow)

    def _disarm(self) -> None:
        if self._read_deadline is not None:
            self._read_deadline.cancel()
            self._read_deadline = None

    def _too_slow(self) -> None:
        self._read_deadline = None
        if self._request_complete() or self.transport.is_closing():
            return
        self.logger.info(
            "closed an HTTP connection whose request was not complete after %.1f s",
            self.request_timeout,
        )
        self.transport.close()


def bounded(timeout_s: float) -> type[BoundedH11Protocol]:
    """The protocol class with a ``timeout_s`` deadline (uvicorn takes a class)."""
    if timeout_s == BoundedH11Protocol.request_timeout:
        return BoundedH11Protocol
    return type("BoundedH11Protocol", (BoundedH11Protocol,), {"request_timeout": timeout_s})
