"""The session recorder: every frame a client sends and receives, as a pcapng file.

Wireshark and tshark open it as TCP traffic: each connection gets synthetic loopback
IPv4/TCP headers with its real ports (the client side gets a made-up ephemeral port
per connection), a three-way handshake, sequence and acknowledgement numbers that
follow the bytes in each direction, and the time each chunk was written or read. So
the Simple Message dissectors (by port 50240/50241/50242) decode it.

The file format and the packets are written by :mod:`pymotoros.capture` (shared
with ``pymotoros sim --record``, which records the twin's side); this module adds
the client's way in. Why dpkt: see there.

Use it as a context manager around the client's work::

    with record_session("session.pcapng"):
        async with RobotClient(host) as robot: ...

Every :class:`~pymotoros.client.connection.FrameConnection` opened inside records
into it (a context variable, so concurrent sessions in other tasks do not mix).
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from pathlib import Path

from pymotoros.capture import CLIENT_IP, FIRST_CLIENT_PORT, SERVER_IP, Flow, SessionRecorder

__all__ = [
    "CLIENT_IP",
    "FIRST_CLIENT_PORT",
    "SERVER_IP",
    "Flow",
    "SessionRecorder",
    "active_flow",
    "record_session",
]

_active: contextvars.ContextVar[SessionRecorder | None] = contextvars.ContextVar(
    "pymotoros_recorder", default=None
)


def active_flow(server_port: int) -> Flow | None:
    """A flow in the active recording for a new connection to ``server_port``, if any."""
    recorder = _active.get()
    return None if recorder is None else recorder.flow(server_port)


@contextlib.contextmanager
def record_session(path: str | Path) -> Iterator[SessionRecorder]:
    """Record every client connection opened inside this block to ``path`` (pcapng)."""
    recorder = SessionRecorder(path)
    token = _active.set(recorder)
    try:
        yield recorder
    finally:
        _active.reset(token)
        recorder.close()
