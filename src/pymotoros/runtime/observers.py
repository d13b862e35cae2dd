"""Who can observe the controller, for the interpolation loop's idle batching (issue 13).

The :class:`~pymotoros.runtime.ticker.Ticker` may run its ticks in batches while nothing
can see the controller between two ticks (see ``runtime/ticker.py``). This module holds
the simulator's side of that bargain:

* :class:`CatchUpMiddleware` (ASGI): every HTTP request and WebSocket first brings the
  controller up to date (``Ticker.catch_up``), and counts as an observer while it is in
  flight (a WebSocket for as long as it is open), so the loop ticks in real time
  meanwhile;
* :class:`Observers`: the ``may_batch`` predicate: no client on any MotoROS port and no
  HTTP request or WebSocket in flight.

The TCP servers call the same catch-up when they accept a connection
(``TcpService.catch_up``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from starlette.types import ASGIApp, Receive, Scope, Send

__all__ = ["CatchUpMiddleware", "Observers"]


class Observers:
    """The predicate "nothing can observe the controller now", and its counters.

    ``clients`` returns the number of clients connected on each MotoROS port;
    ``catch_up`` brings the controller up to date (the ticker's).
    """

    def __init__(
        self,
        clients: Callable[[], Iterable[int]],
        catch_up: Callable[[], object],
    ) -> None:
        self._clients = clients
        self.catch_up = catch_up
        self.web = 0
        """HTTP requests and WebSockets in flight."""

    def may_batch(self) -> bool:
        """True when no client is connected and no web request is in flight."""
        return self.web == 0 and not any(self._clients())


class CatchUpMiddleware:
    """ASGI middleware: catch the controller up before serving a request or WebSocket,
    and count it as an observer while it runs."""

    def __init__(self, app: ASGIApp, observers: Observers) -> None:
        self.app = app
        self.observers = observers

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        observers = self.observers
        observers.web += 1
        try:
            observers.catch_up()
            await self.app(scope, receive, send)
        finally:
            observers.web -= 1
