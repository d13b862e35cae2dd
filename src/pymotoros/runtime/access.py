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

The configured token is trimmed of the whitespace around it (a Kubernetes Secret made
from a file ends in a newline, and clients' headers are trimmed too); whitespace inside
is refused at start. Beyond loopback a token must not be guessable: 16 characters at
least and no placeholder copied from an example (:func:`weak_token`; the CLI and
:class:`~pymotoros.runtime.app.SimulatorConfig` refuse it). With a token the OpenAPI
document declares the bearer scheme and each guarded operation's 401
(:func:`document_security`), so ``/docs`` has an Authorize button.

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
from typing import Any, Final
from urllib.parse import parse_qs

from fastapi import FastAPI
from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

from pymotoros.runtime.log_limit import api_refusal_allowed

__all__ = [
    "MIN_TOKEN_LENGTH",
    "PLACEHOLDER_TOKENS",
    "TOKEN_ENV",
    "AccessGuard",
    "clean_token",
    "document_security",
    "guarded",
    "install_access",
    "loopback_or_token",
    "weak_token",
]

logger = logging.getLogger(__name__)

TOKEN_ENV: Final = "PYMOTOROS_TOKEN"  # noqa: S105 - a variable's name, not a secret
"""Environment variable read by ``pymotoros sim`` when ``--token`` is not given."""

MIN_TOKEN_LENGTH: Final = 16
"""The shortest token accepted beyond loopback: 16 random characters (~95 bits from
``python -c 'import secrets; print(secrets.token_urlsafe(16))'``, 22 characters) cannot
be guessed over HTTP; a word or a PIN can."""
PLACEHOLDER_TOKENS: Final = frozenset(
    {
        "change-me-before-applying",  # the example Secret once shipped in deploy/k8s
        "changeme",
        "change-me",
        "change_me",
        "changeit",
        "replace-me",
        "replaceme",
        "secret",
        "token",
        "password",
        "passw0rd",
        "admin",
        "default",
        "example",
        "test",
        "pymotoros",
        "s3cret",
        "your-token-here",
        "<token>",
        "token-goes-here",
    }
)
"""Tokens copied from an example rather than made (compared without case): refused
beyond loopback whatever their length. All but ``change-me-before-applying`` are shorter
than MIN_TOKEN_LENGTH and would be refused by the length rule too; they stay because their
refusal says the better thing (a copied placeholder, not a secret: anybody who read the
example has it) than "too short", which invites padding the placeholder."""
MAKE_ONE: Final = "make one with: python -c 'import secrets; print(secrets.token_urlsafe(24))'"
"""How to make a token, in the words of a refusal."""

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


def clean_token(token: str | None, *, source: str = "--token") -> str | None:
    """The token without the whitespace around it (a Kubernetes Secret made from a file
    ends in a newline; clients' headers are trimmed too); None for none or an empty one.
    A token with whitespace *inside* cannot be sent in one header value as given:
    :class:`ValueError` saying so. So does one with a character beyond ASCII: HTTP
    clients encode it differently (UTF-8, latin-1) and the server reads the header as
    latin-1, so it would match for one client and not another."""
    if token is None:
        return None
    trimmed = token.strip()
    if any(c.isspace() for c in trimmed):
        raise ValueError(
            f"{source}: the token contains whitespace inside ({len(trimmed)} characters); "
            f"a bearer token is one word: {MAKE_ONE}"
        )
    if not trimmed.isascii():
        raise ValueError(
            f"{source}: the token contains characters beyond ASCII ({len(trimmed)} "
            "characters); HTTP clients send them in different encodings, so it would "
            f"match for some and not others: {MAKE_ONE}"
        )
    return trimmed or None


def weak_token(token: str, host: str, *, source: str = "--token") -> str | None:
    """Why ``token`` is too weak to guard a control API on ``host`` beyond loopback
    (None: it will do). The caller decides whether ``host`` is loopback."""
    if token.lower() in PLACEHOLDER_TOKENS:
        return (
            f"{source}: the token is the placeholder {token!r}, not a secret: anybody who "
            f"read the example can use the control API on {host}; {MAKE_ONE}"
        )
    if len(token) < MIN_TOKEN_LENGTH:
        return (
            f"{source}: the token has {len(token)} characters; beyond loopback ({host}) "
            f"it needs at least {MIN_TOKEN_LENGTH} so that it cannot be guessed; "
            f"{MAKE_ONE}"
        )
    return None


class AccessGuard:
    """ASGI middleware: 401 for a guarded path without ``Authorization: Bearer TOKEN``."""

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self._token = token.encode()  # cleaned once, by SimulatorConfig
        if not self._token:
            raise ValueError("AccessGuard needs a token that is not empty")

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
    """Add ``/healthz`` and ``/readyz``; require ``token`` when given (as
    :func:`clean_token` returned it: SimulatorConfig cleans it once)."""

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
        document_security(api)


BEARER_SCHEME: Final = "bearerAuth"
"""The security scheme's name in the OpenAPI document."""


def document_security(api: FastAPI) -> None:
    """Declare the bearer token in ``api``'s OpenAPI document: the scheme (the /docs
    page's Authorize button sends it), and on every guarded operation its requirement
    and the 401 answer (generated clients then know both)."""
    build = api.openapi

    def openapi() -> dict[str, Any]:
        if api.openapi_schema is not None:
            return api.openapi_schema
        schema = build()
        components = schema.setdefault("components", {})
        components.setdefault("securitySchemes", {})[BEARER_SCHEME] = {
            "type": "http",
            "scheme": "bearer",
            "description": "the token given to pymotoros sim --token (or PYMOTOROS_TOKEN)",
        }
        error: dict[str, Any] = {"$ref": "#/components/schemas/ErrorModel"}
        if "ErrorModel" not in components.get("schemas", {}):
            error = {
                "type": "object",
                "properties": {"error": {"type": "string"}},
                "required": ["error"],
            }
        for path, operations in schema.get("paths", {}).items():
            if not guarded(path):
                continue
            for operation in operations.values():
                operation["security"] = [{BEARER_SCHEME: []}]
                operation.setdefault("responses", {})["401"] = {
                    "description": "no token, or a wrong one (the error says how to send it)",
                    "headers": {"WWW-Authenticate": {"schema": {"type": "string"}}},
                    "content": {"application/json": {"schema": error}},
                }
        api.openapi_schema = schema
        return schema

    api.openapi = openapi  # type: ignore[method-assign]
