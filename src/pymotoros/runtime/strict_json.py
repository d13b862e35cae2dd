"""JSON bodies of the control API with a key given twice are refused (issue 13: nothing
silently accepted).

Python's ``json.loads`` keeps the last of two equal keys, so ``{"value": 1, "value": 0}``
would force an output *off* without a word, where another JSON parser in front of the
twin (a proxy, a test tool) may have read it as *on*. :class:`StrictJsonRoute` parses
every JSON request body once, with a hook that notices a repeated key in any object at
any depth, and answers 422 ``{"error": "..."}`` (the shape of the API's other malformed
body errors) naming the key and where it is. A body without repeated keys is handed to
FastAPI already parsed, so it is still parsed only once: the route passes FastAPI a
:class:`Request` subclass whose ``json()`` returns that parse (the extension point
FastAPI documents as a custom Request class; FastAPI reads JSON bodies through
``Request.json()``). A body that is not valid JSON is left to FastAPI, whose error the
API reports as before.

It runs behind :class:`~pymotoros.runtime.body_limit.BodyLimit`, so a body reaching it
is at most ``MAX_BODY_BYTES`` long and ``MAX_JSON_DEPTH`` deep.
"""

from __future__ import annotations

import email.message
import json
import logging
from collections.abc import Callable, Coroutine
from typing import Any, Final

from fastapi.datastructures import DefaultPlaceholder
from fastapi.routing import APIRoute
from starlette.requests import Request
from starlette.responses import JSONResponse, Response

from pymotoros.errors import PymotorosError
from pymotoros.runtime.log_limit import api_refusal_allowed

__all__ = ["DuplicateKeyError", "StrictJsonRoute", "loads_strict"]

logger = logging.getLogger(__name__)

DUPLICATE_KEY_STATUS: Final = 422
"""The control API's status for a malformed body (the same as invalid JSON)."""


class DuplicateKeyError(PymotorosError, ValueError):
    """A JSON object names the same key more than once."""

    def __init__(self, key: str, where: str) -> None:
        super().__init__(f"the key {key!r} is given more than once in {where}")
        self.key = key
        self.where = where


class _Pairs(list[tuple[str, Any]]):
    """A JSON object as the parser saw it: its (key, value) pairs in order, repeats kept."""


def _no_repeats(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    obj = dict(pairs)
    if len(obj) != len(pairs):
        raise _RepeatedKeyError
    return obj


class _RepeatedKeyError(Exception):
    """Internal: the parse met a repeated key (found again with its place by :func:`_locate`)."""


def _locate(value: Any, where: str) -> DuplicateKeyError | None:
    """The first repeated key in a body parsed into :class:`_Pairs`, and where it is."""
    if isinstance(value, _Pairs):
        seen: set[str] = set()
        for key, _ in value:
            if key in seen:
                return DuplicateKeyError(key, f"the object at {where}" if where else "the body")
            seen.add(key)
        for key, item in value:
            found = _locate(item, f"{where}.{key}" if where else key)
            if found is not None:
                return found
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found = _locate(item, f"{where}[{index}]")
            if found is not None:
                return found
    return None


def loads_strict(body: bytes | str) -> Any:
    """``json.loads``, refusing an object that names a key twice (:class:`DuplicateKeyError`)."""
    try:
        return json.loads(body, object_pairs_hook=_no_repeats)
    except _RepeatedKeyError:
        # Only now, on the error path: parse again keeping every pair, to say where.
        found = _locate(json.loads(body, object_pairs_hook=_Pairs), "")
        if found is None:  # pragma: no cover - the first parse met a repeat
            raise DuplicateKeyError("?", "the body") from None
        raise found from None


def _is_json(content_type: str | None, strict_content_type: bool) -> bool:
    """Whether FastAPI parses a body with this Content-Type as JSON (the same rule)."""
    if not content_type:
        return not strict_content_type
    message = email.message.Message()
    message["content-type"] = content_type
    if message.get_content_maintype() != "application":
        return False
    subtype = message.get_content_subtype()
    return subtype == "json" or subtype.endswith("+json")


_UNPARSED: Final = object()


class _CheckedRequest(Request):
    """A request whose JSON body the duplicate-key check has parsed: ``json()`` returns
    that parse instead of parsing the same bytes again."""

    checked: Any = _UNPARSED

    async def json(self) -> Any:
        if self.checked is _UNPARSED:
            return await super().json()
        return self.checked


class StrictJsonRoute(APIRoute):
    """An API route whose JSON body may not name a key twice in any object."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()
        if self.body_field is None:  # takes no body: FastAPI never reads it
            return handler
        strict: object = getattr(self, "strict_content_type", False)  # FastAPI >= 0.120
        if isinstance(strict, DefaultPlaceholder):
            strict = strict.value
        strict_content_type = bool(strict)

        async def handle(original: Request) -> Response:
            # Nothing has read the body yet: this request takes the original's place.
            request = _CheckedRequest(original.scope, original.receive)
            if _is_json(request.headers.get("content-type"), strict_content_type):
                body = await request.body()
                if body:
                    try:
                        request.checked = loads_strict(body)
                    except DuplicateKeyError as exc:
                        return _refuse(request, exc)
                    except (ValueError, RecursionError):
                        pass  # not JSON: FastAPI parses it again and reports it as before
            return await handler(request)

        return handle


def _refuse(request: Request, exc: DuplicateKeyError) -> JSONResponse:
    message = (
        f"{request.method} {request.url.path}: {exc}; JSON parsers disagree on which of "
        "the values counts, so the control API takes none: send each key once"
    )
    if api_refusal_allowed(request.scope, logger, logging.INFO):  # a flood: counted
        logger.info("control API refused a request: %s", message)
    return JSONResponse({"error": message}, status_code=DUPLICATE_KEY_STATUS)
