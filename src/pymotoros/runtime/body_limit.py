"""A bound on the control API's request bodies: size and JSON nesting depth.

Starlette reads a request body into memory whole, however large, and Python's JSON
parser recurses once per nesting level: a client could make the simulator hold a 50 MB
body (or an endless chunked one) in memory, or fail deep inside the parser with a
message that says nothing useful. :class:`BodyLimit` sits in front of the application,
reads the body of every request that carries one up to :data:`MAX_BODY_BYTES` and no
further, and answers itself:

- 413 with ``{"error": ...}`` when the body is larger (announced by ``Content-Length``
  or found while reading a chunked body): the rest is never read, and uvicorn closes the
  connection after the answer, as HTTP/1.1 allows for an unread body;
- 400 when a JSON body nests deeper than :data:`MAX_JSON_DEPTH`.

The body it read is then handed on to the application unchanged, so memory per request
is bounded by :data:`MAX_BODY_BYTES` whatever the client sends.
"""

from __future__ import annotations

import logging
import re
from typing import Final

from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from pymotoros.runtime.log_limit import api_refusal_allowed

__all__ = ["MAX_BODY_BYTES", "MAX_JSON_DEPTH", "BodyLimit", "nests_deeper_than"]

logger = logging.getLogger(__name__)

MAX_BODY_BYTES: Final = 256 * 1024
"""256 KiB. The largest body the control API takes is ``POST /api/scenario``'s event
list (a few dozen bytes per event): 256 KiB is ~3,000 events, far more than a scenario
file holds; small enough that a hundred clients at once stay within a few tens of MB,
and that checking a body's nesting holds the event loop for a few milliseconds at most."""

MAX_JSON_DEPTH: Final = 32
"""Deepest JSON nesting accepted. The API's bodies nest at most 3 levels (a scenario: an
object holding a list of objects); Python's JSON parser gives up near 1,000 levels with
an error that names no cause, so anything deeper than this is refused first, by name."""

_STRING: Final = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)
"""A JSON string literal (brackets inside strings do not nest anything)."""

_NOT_BRACKETS: Final = bytes(b for b in range(256) if b not in b"[]{}")
_ONE_KIND: Final = bytes.maketrans(b"{}", b"[]")
"""Nesting depth does not depend on the kind of bracket: objects count as lists."""

_BODY_METHODS: Final = frozenset({"POST", "PUT", "PATCH", "DELETE"})
"""Methods whose requests carry a body the control API reads."""


def _reduces_within(text: bytes, depth: int) -> bool:
    """Whether the brackets of ``text`` are balanced and nest at most ``depth`` levels:
    every bracket becomes ``[``/``]``, and each round removes the innermost level."""
    skeleton = text.translate(_ONE_KIND, _NOT_BRACKETS)
    if b"[" * (depth + 1) in skeleton:  # the usual attack: a straight run of openings
        return False
    for _ in range(depth):
        if not skeleton:
            return True
        skeleton = skeleton.replace(b"[]", b"")
    return not skeleton


def nests_deeper_than(body: bytes, depth: int) -> bool:
    """Whether a JSON text nests ``[``/``{`` more than ``depth`` levels (exact for valid
    JSON; unbalanced brackets count as deep).

    First with strings left in: if the brackets, those in strings included, balance
    within ``depth`` levels, the JSON's own (a subsequence with the strings' balanced
    contents removed) do too. Only otherwise are the strings dropped (a regular
    expression: the one step that costs a few milliseconds on a body of
    :data:`MAX_BODY_BYTES`) and the count redone. Everything runs in C (``bytes.count``,
    ``translate``, ``replace``, ``re``), where a Python loop over the bytes would hold
    the event loop for tens of milliseconds.
    """
    if body.count(b"[") + body.count(b"{") <= depth:
        return False
    if _reduces_within(body, depth):
        return False
    return not _reduces_within(_STRING.sub(b"", body), depth)


def _may_nest_too_deep(body: bytes, headers: Headers) -> bool:
    """Whether the body needs :func:`nests_deeper_than` at all: a JSON body with more opening
    brackets than :data:`MAX_JSON_DEPTH` (two C-speed counts; every usual body has few)."""
    content_type = headers.get("content-type", "")
    if content_type and "json" not in content_type:  # FastAPI parses untyped bodies as JSON
        return False
    return body.count(b"[") + body.count(b"{") > MAX_JSON_DEPTH


class BodyLimit:
    """ASGI middleware: read at most :data:`MAX_BODY_BYTES` of a request body; refuse
    larger (413) or too deeply nested JSON (400) bodies before the application sees them."""

    def __init__(self, app: ASGIApp, max_bytes: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] not in _BODY_METHODS:
            await self.app(scope, receive, send)
            return
        path = scope.get("path", "")
        headers = Headers(scope=scope)
        announced = headers.get("content-length")
        if announced is not None and announced.isdigit() and int(announced) > self.max_bytes:
            await self._refuse(scope, receive, send, 413, self._too_large(path, int(announced)))
            return
        chunks: list[bytes] = []
        size = 0
        more = True
        while more:
            message = await receive()
            if message["type"] != "http.request":  # the client went away
                return
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.max_bytes:
                await self._refuse(scope, receive, send, 413, self._too_large(path, None))
                return
            chunks.append(chunk)
            more = message.get("more_body", False)
        body = b"".join(chunks)
        if _may_nest_too_deep(body, headers) and nests_deeper_than(body, MAX_JSON_DEPTH):
            message_text = (
                f"{scope['method']} {path}: the JSON body nests deeper than {MAX_JSON_DEPTH} "
                "levels; the control API's bodies are flat objects (see /docs)"
            )
            await self._refuse(scope, receive, send, 400, message_text)
            return

        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()  # after the body: waits for the disconnect

        await self.app(scope, replay, send)

    def _too_large(self, path: str, announced: int | None) -> str:
        size = f"{announced} bytes" if announced is not None else "a body"
        return (
            f"{path}: {size} is more than the control API takes ({self.max_bytes} bytes); "
            "its bodies are small JSON objects (see /docs)"
        )

    @staticmethod
    async def _refuse(scope: Scope, receive: Receive, send: Send, status: int, text: str) -> None:
        if api_refusal_allowed(scope, logger, logging.INFO):  # a flood: counted
            logger.info("control API refused a request: %s", text)
        await JSONResponse({"error": text}, status_code=status)(scope, receive, send)
