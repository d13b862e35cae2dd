"""Which ``Host`` the control API answers to: a guard against DNS rebinding.

A page on ``http://rebind.attacker.example:8080`` can make its own name resolve to
127.0.0.1 a moment after it loaded. The browser then sends the page's requests to the
twin, as *same-origin* requests: ``Origin`` and ``Host`` both say
``rebind.attacker.example:8080``, so the CSRF guard (which compares the two) lets them
through, and the page can read ``GET /api/state`` and press E-stop. What gives such a
request away is the name in ``Host``: the twin was never called that. So every request
(HTTP and the WebSocket handshake) whose ``Host`` is not one of the twin's own names is
refused with 403 and a body naming the Host and how to allow it.

The twin's own names:

* the loopback names ``localhost``, ``127.0.0.1`` and ``[::1]``;
* the address it listens on (``pymotoros sim --host``);
* when it listens on every interface (``0.0.0.0`` or ``::``, a container): the
  machine's host name (a container's or a pod's name) and any IP address. An address
  written as digits cannot be the product of a DNS rebinding (no name was resolved),
  and a container cannot know under which address it is published (``docker run -p``,
  a Kubernetes pod IP the probes and Prometheus use). Beyond loopback the token is
  mandatory anyway (runtime/access.py);
* the names the user adds: ``pymotoros sim --allowed-host NAME`` (repeatable; also
  ``PYMOTOROS_SIM_ALLOWED_HOST`` and ``allowed_host`` in the settings file's ``[sim]``
  table). ``.example.com`` (or ``*.example.com``, the same) allows the domain and every
  name under it (a Kubernetes Service's ``.svc.cluster.local``), ``*`` allows any name
  (turns the guard off); a ``*`` anywhere else is refused (it would match nothing).

The port in ``Host`` is not compared: a rebinding page reaches the twin on the port it
serves anyway, and a published port (``-p 9000:8080``, ``kubectl port-forward``) changes
the number the client writes. A request without ``Host`` (HTTP/1.0 from a script) is not
a browser's and passes.
"""

from __future__ import annotations

import ipaddress
import logging
import socket
from collections.abc import Iterable
from typing import Final

from starlette.datastructures import Headers
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

from pymotoros.runtime.log_limit import api_refusal_allowed

__all__ = [
    "ALLOWED_HOST_OPTION",
    "LOOPBACK_NAMES",
    "HostGuard",
    "OwnNames",
    "allowed_name",
    "host_name",
    "own_names",
]

logger = logging.getLogger(__name__)

LOOPBACK_NAMES: Final = ("localhost", "127.0.0.1", "::1")
"""Always the twin's own: a loopback client names it so."""
WILDCARD_HOSTS: Final = frozenset({"0.0.0.0", "::", ""})  # noqa: S104 - names, not a bind
"""Listen addresses meaning "every interface"."""
ALLOWED_HOST_OPTION: Final = "--allowed-host"
"""``pymotoros sim``'s option that adds a name (the refusal's words name it)."""
ANY_HOST: Final = "*"


def host_name(header: str) -> str:
    """The name in a ``Host`` header, without its port, brackets or final dot, lowercase:
    ``[::1]:8080`` -> ``::1``, ``Twin.Local.:80`` -> ``twin.local``."""
    value = header.strip().lower()
    if value.startswith("["):  # an IPv6 literal: [addr]:port
        end = value.find("]")
        return value[1:end] if end > 0 else value
    if value.count(":") == 1:
        value = value.partition(":")[0]
    return value.rstrip(".")


def allowed_name(raw: str) -> str:
    """A name as the user wrote it (``--allowed-host``), in the form the guard compares:
    ``Twin.Lab:8080`` -> ``twin.lab``, ``*.Lab.Example`` -> ``.lab.example`` (a suffix),
    ``*`` stays. ValueError for a ``*`` elsewhere (``twin-*``): no Host would match it."""
    value = raw.strip().lower()
    if value == ANY_HOST:
        return value
    if value.startswith(("*.", ".")):
        suffix = value.removeprefix("*").rstrip(".")
        rest = suffix[1:]
    else:
        suffix = ""
        rest = host_name(value)
    if ANY_HOST in rest:
        raise ValueError(
            f"allowed host {raw!r}: '*' stands only alone (any name) or as '*.example.com' "
            "(every name under example.com, also written .example.com); a pattern such as "
            "'twin-*' is not supported: list the names"
        )
    return suffix if suffix else rest


def _is_ip(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


class OwnNames:
    """The names the twin answers to (see the module's docstring)."""

    def __init__(self, names: Iterable[str], *, any_ip: bool = False) -> None:
        exact: set[str] = set()
        suffixes: list[str] = []
        self.any_name = False
        for raw in names:
            name = allowed_name(raw)
            if name == ANY_HOST:
                self.any_name = True
            elif name.startswith("."):
                suffixes.append(name)
            elif name:
                exact.add(name)
        self.exact = frozenset(exact)
        self.suffixes = tuple(suffixes)
        self.any_ip = any_ip

    def __contains__(self, name: object) -> bool:
        if not isinstance(name, str):
            return False
        if self.any_name or name in self.exact:
            return True
        if any(name == s[1:] or name.endswith(s) for s in self.suffixes):
            return True
        return self.any_ip and _is_ip(name)

    def describe(self) -> str:
        """The names in the words of an error: ``localhost, 127.0.0.1, [::1], twin-0``."""
        shown = [f"[{n}]" if ":" in n else n for n in sorted(self.exact, key=_order)]
        shown += list(self.suffixes)  # as they are written: .example.com
        if self.any_ip:
            shown.append("any IP address")
        return ", ".join(shown)


def _order(name: str) -> tuple[int, str]:
    return (LOOPBACK_NAMES.index(name) if name in LOOPBACK_NAMES else len(LOOPBACK_NAMES), name)


def own_names(listen_host: str, allowed: Iterable[str] = ()) -> OwnNames:
    """The twin's own names when it listens on ``listen_host``, plus ``allowed``."""
    names = [*LOOPBACK_NAMES, *allowed]
    wildcard = listen_host.strip("[]") in WILDCARD_HOSTS
    if wildcard:
        names.append(socket.gethostname())  # a container's (pod's) own name
    else:
        names.append(listen_host)
    return OwnNames(names, any_ip=wildcard)


class HostGuard:
    """ASGI middleware: 403 for a request (or a WebSocket handshake) whose ``Host`` is
    not one of ``names``."""

    def __init__(self, app: ASGIApp, names: OwnNames) -> None:
        self.app = app
        self.names = names

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        kind = scope["type"]
        if kind not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        header = Headers(scope=scope).get("host")
        name = host_name(header) if header is not None else None
        if name is None or name in self.names:
            await self.app(scope, receive, send)
            return
        shown = f"[{name}]" if ":" in name else name
        message = (
            f"refused a request for Host {header!r}: this twin answers only to its own "
            f"names ({self.names.describe()}); a page under another name may be a DNS "
            "rebinding attack. If you reach the twin under that name, allow it: "
            f"pymotoros sim {ALLOWED_HOST_OPTION} {shown} (repeatable; also "
            "allowed_host in the settings file's [sim] table)"
        )
        if api_refusal_allowed(scope, logger, logging.WARNING):  # a flood: counted
            logger.warning("%s", message)
        response = JSONResponse({"error": message}, status_code=403)
        if kind == "websocket":
            if "websocket.http.response" in scope.get("extensions", {}):
                await response(scope, receive, send)  # Starlette sends it as websocket.http.*
            else:  # the server cannot answer with a status: refuse the handshake (403)
                await send({"type": "websocket.close", "code": 1008, "reason": "host"})
            return
        await response(scope, receive, send)
