"""The client's three connections to a controller: which are open, opening, closing.

The connection part of :class:`~pymotoros.client.RobotClient`. MotoROS accepts one
motion and one IO connection at a time, so a command opens only the ports it needs;
every other part asks :meth:`Link.need` for its port and gets a one-line error naming
what to connect when it is not open.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import KW_ONLY, dataclass, field

from pymotoros.client.connection import (
    Connector,
    FrameConnection,
    Ports,
    stop_queued_motion,
)
from pymotoros.client.errors import ClientError, ConnectionLostError
from pymotoros.protocol.constants import ByteOrder, Port
from pymotoros.protocol.messages import WireMessage

_MOTION, _STATE, _IO = Port.MOTION, Port.STATE, Port.IO


@dataclass(eq=False, repr=False)
class Link:
    """Host, ports and byte order, and the motion, state and IO connections once open."""

    host: str
    ports: Ports
    order: ByteOrder
    _: KW_ONLY
    timeout_s: float
    connect_timeout_s: float
    connector: Connector | None = None
    motion: FrameConnection | None = field(default=None, init=False)
    state: FrameConnection | None = field(default=None, init=False)
    io: FrameConnection | None = field(default=None, init=False)
    loop: asyncio.AbstractEventLoop | None = field(default=None, init=False)
    """The event loop the connections live on (set by :meth:`open`)."""

    async def open(
        self,
        *,
        motion: bool,
        state: bool,
        io: bool,
        on_state: Callable[[WireMessage], None],
        on_state_lost: Callable[[ConnectionLostError], None],
    ) -> None:
        """Open the ports asked for; on any failure close what was opened and raise."""
        self.loop = asyncio.get_running_loop()
        try:
            if motion:
                self.motion = await self._open(Port.MOTION)
                # A closed connection's queued increments run from now on (§2.2): stop them.
                await stop_queued_motion(self.motion, timeout_s=self.timeout_s)
            if state:
                self.state = await self._open(Port.STATE, on_state, on_state_lost)
            if io:
                self.io = await self._open(Port.IO)
        except BaseException:
            await self.close()
            raise

    async def _open(
        self,
        kind: Port,
        on_topic: Callable[[WireMessage], None] | None = None,
        on_lost: Callable[[ConnectionLostError], None] | None = None,
    ) -> FrameConnection:
        return await FrameConnection.open(
            self.host,
            self.ports.of(kind),
            kind,
            self.order,
            timeout_s=self.connect_timeout_s,
            on_topic=on_topic,
            on_lost=on_lost,
            connector=self.connector,
        )

    async def close(self) -> None:
        """Close every connection (trajectory mode is left as it is). Idempotent."""
        for conn in (self.io, self.state, self.motion):
            if conn is not None:
                await conn.close()

    def need(self, kind: Port) -> FrameConnection:
        """The open connection of ``kind``, or a ClientError saying how to open it."""
        # Identity tests, not a dict keyed by Port: Enum hashing is a Python call, and
        # the motion port is asked for once per trajectory point.
        if kind is _MOTION:
            conn = self.motion
        elif kind is _STATE:
            conn = self.state
        elif kind is _IO:
            conn = self.io
        else:
            raise KeyError(kind)
        if conn is None:
            raise ClientError(
                f"the {kind.value} port is not connected (connect({kind.value}=True))"
            )
        return conn

    def io_or_motion(self) -> FrameConnection:
        """The IO connection, else the motion one (MotoROS answers IO bits on both)."""
        if self.io is None and self.motion is not None:
            return self.motion
        return self.need(Port.IO)
