"""Cross-site request forgery guard for the control API.

The pendant page can press E-stop, switch modes and force IO. A browser that has the
page of *another* site open could otherwise post to ``http://localhost:8080/api/...``
(a "simple" cross-origin form POST needs no CORS pre-flight). Browsers always send
``Origin`` (and usually ``Referer``) on such requests, so a state-changing request whose
origin is not the simulator's own is refused with 403. Requests without either header
(curl, the Python client, scripts) are not from a browser page and stay allowed.
"""

from __future__ import annotations

import logging
from typing import Final
from urllib.parse import urlsplit

from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from pymotoros.runtime.log_limit import api_refusal_allowed

__all__ = ["FRAME_HEADERS", "CsrfGuard", "NoFraming", "same_origin"]

logger = logging.getLogger(__name__)

SAFE_METHODS: Final = frozenset({"GET", "HEAD", "OPTIONS"})
"""Methods that change nothing (RFC 9110 §9.2.1): never checked."""


FRAME_HEADERS: Final = (
    (b"x-frame-options", b"SAMEORIGIN"),
    (b"content-security-policy", b"frame-ancestors 'self'"),
)
"""What stops another site from framing the pendant (or /docs) under a decoy and
luring a click onto E-STOP or SERVO ("clickjacking"): the old header every browser
knows, and its CSP successor. A response that has its own CSP (the docs pages) keeps
it; that policy names ``frame-ancestors`` itself (runtime/docs_page.py)."""


def _origin_of(url: str) -> str | None:
    parts = urlsplit(url)
    if not parts.scheme or not parts.netloc:
        return None
    return f"{parts.scheme}://{parts.netloc}".lower()


def same_origin(headers: Headers, scheme: str) -> tuple[bool, str]:
    """Whether a request's ``Origin`` (else ``Referer``) is this server's own origin
    (``scheme://Host``); answers (ok, the origin seen, "" when the header is absent)."""
    host = headers.get("host", "").lower()
    own = f"{scheme}://{host}"
    seen = headers.get("origin")
    if seen is None:
        referer = headers.get("referer")
        if referer is None:
            return True, ""
        seen = _origin_of(referer) or referer
    seen = seen.lower()
    return seen == own, seen


class CsrfGuard:
    """ASGI middleware: refuse state-changing requests, and WebSocket handshakes, whose
    ``Origin``/``Referer`` is another site."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind == "http" and scope["method"] not in SAFE_METHODS:
            scheme = scope.get("scheme", "http")
        elif kind == "websocket":
            scheme = "https" if scope.get("scheme") == "wss" else "http"
        else:
            await self.app(scope, receive, send)
            return
        ok, seen = same_origin(Headers(scope=scope), scheme)
        if ok:
            await self.app(scope, receive, send)
            return
        path = scope.get("path", "")
        message = (
            f"refused a cross-site request to {path} from origin {seen!r}: only pages served "
            "by this simulator may change its state (send no Origin header from scripts)"
        )
        if api_refusal_allowed(scope, logger, logging.WARNING):  # a flood: counted
            logger.warning("%s", message)
        if kind == "websocket":
            await send({"type": "websocket.close", "code": 1008, "reason": "cross-site"})
            return
        await JSONResponse({"error": message}, status_code=403)(scope, receive, send)


class NoFraming:
    """ASGI middleware: every HTTP answer may be framed by this server's pages only
    (:data:`FRAME_HEADERS`)."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                present = {name.lower() for name, _ in headers}
                headers += [(k, v) for k, v in FRAME_HEADERS if k not in present]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, with_headers)
