"""Who may use the control API: an optional bearer token, and the health endpoint.

The control API can E-stop the robot, switch modes and force IO. On loopback (the
default) the CSRF guard is enough; bound to other interfaces (a container, a cluster)
anybody who can reach the port could press buttons. ``pymotoros sim --token TOKEN`` (or
``PYMOTOROS_TOKEN``) makes every ``/api`` route, ``/metrics`` and the ``/ws/state`` feed
require ``Authorization: Bearer TOKEN``; anything else gets 401 with a message saying
what to send. Browsers cannot put a header on a WebSocket handshake, so the feed also
takes the token as ``?access_token=TOKEN`` (RFC 6750 §2.3); the pendant page and its
static files stay open (they hold no state) and the page asks for the token once,
keeping it in ``sessionStorage`` for the tab's session (``/pendant/access.js``, loaded
before the pendant's own script: it adds the token to every ``fetch`` and feed).

``GET /healthz`` (liveness: the process serves) and ``GET /readyz`` (readiness: the
MotoROS ports listen, else 503) are always open: Kubernetes probes cannot read a Secret
into a header, and they tell nothing an attacker could use.

The MotoROS ports themselves (50240-50242) stay as open as on a real controller: MotoROS
has no authentication, and a client written for the robot must work unchanged against
the twin. Protect them with the network (a private Service, a NetworkPolicy).
"""

from __future__ import annotations

import hmac
import logging
from collections.abc import Callable
from typing import Final
from urllib.parse import parse_qs

from fastapi import FastAPI
from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

from pymotoros.runtime.log_limit import api_refusal_allowed

__all__ = [
    "TOKEN_ENV",
    "AccessGuard",
    "guarded",
    "install_access",
    "loopback_or_token",
]

logger = logging.getLogger(__name__)

TOKEN_ENV: Final = "PYMOTOROS_TOKEN"  # noqa: S105 - a variable's name, not a secret
"""Environment variable read by ``pymotoros sim`` when ``--token`` is not given."""

GUARDED_PREFIXES: Final = ("/api/", "/ws/")
GUARDED_PATHS: Final = frozenset({"/api", "/metrics"})


def guarded(path: str) -> bool:
    """Does ``path`` need the token? Every /api route, /metrics and every /ws feed."""
    return path in GUARDED_PATHS or path.startswith(GUARDED_PREFIXES)


def _presented(scope: Scope) -> str | None:
    auth = Headers(scope=scope).get("authorization")
    if auth is not None:
        scheme, _, value = auth.partition(" ")
        return value.strip() if scheme.lower() == "bearer" else None
    if scope["type"] == "websocket":
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        values = query.get("access_token")
        return values[0] if values else None
    return None


class AccessGuard:
    """ASGI middleware: 401 for a guarded path without ``Authorization: Bearer TOKEN``."""

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self._token = token.encode()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket") or not guarded(scope.get("path", "")):
            await self.app(scope, receive, send)
            return
        given = _presented(scope)
        if given is not None and hmac.compare_digest(given.encode(), self._token):
            await self.app(scope, receive, send)
            return
        path = scope.get("path", "")
        why = "no token" if given is None else "a wrong token"
        message = (
            f"{path} needs the control API's token and the request had {why}: send "
            "'Authorization: Bearer TOKEN' (the token given to pymotoros sim --token or "
            "PYMOTOROS_TOKEN)"
        )
        if api_refusal_allowed(scope, logger, logging.WARNING):
            logger.warning("refused %s %s: %s", kind, path, why)
        response = JSONResponse(
            {"error": message}, status_code=401, headers={"WWW-Authenticate": "Bearer"}
        )
        if kind == "websocket":
            if "websocket.http.response" in scope.get("extensions", {}):
                await response(scope, receive, send)  # Starlette sends it as websocket.http.*
            else:  # the server cannot answer with a status: refuse the handshake (403)
                await send({"type": "websocket.close", "code": 1008, "reason": "token"})
            return
        await response(scope, receive, send)


def loopback_or_token(host: str, token: str | None, insecure: bool) -> str | None:
    """Why the control API must not start (None: it may). ``is_loopback`` is the caller's."""
    if token or insecure:
        return None
    return (
        f"the control API would listen on {host} without a token: anybody who reaches "
        "that address could E-stop, move and force IO on the twin. Give --token TOKEN "
        f"(or {TOKEN_ENV}), or --insecure-http to allow it anyway"
    )


def install_access(
    api: FastAPI, token: str | None, *, ready: Callable[[], bool] | None = None
) -> None:
    """Add ``/healthz`` and ``/readyz``; require ``token`` when given."""

    @api.get("/healthz", include_in_schema=False)
    async def healthz() -> dict[str, str]:
        """200 while the process serves HTTP (the liveness probe; never guarded)."""
        return {"status": "ok"}

    @api.get("/readyz", include_in_schema=False)
    async def readyz() -> JSONResponse:
        """200 once the MotoROS ports listen, else 503 (the readiness probe; never guarded)."""
        listening = ready() if ready is not None else True
        return JSONResponse(
            {"status": "ready" if listening else "starting", "motoros_listening": listening},
            status_code=200 if listening else 503,
        )

    if token:
        api.add_middleware(AccessGuard, token=token)
