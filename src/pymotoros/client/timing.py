"""Where the client gets its time from: "now" and "sleep", injectable.

The client never calls ``time.monotonic`` or ``asyncio.sleep`` in its motion logic
(BUSY back-off, following monitor, completion deadlines); it asks a
:class:`ClientClock`. The default, :data:`REAL_TIME`, is the wall clock. The
in-memory twin (:mod:`pymotoros.testing`) passes a virtual clock whose ``sleep``
advances the twin's time (running controller ticks) instead of waiting, so a
minute of motion is tested in a fraction of a second, as the controller's own
clock (``pymotoros.runtime.clock``) already allows.

Request and state *timeouts* stay on the event loop's clock: they bound how long
the client waits for a peer, which in a twin that runs faster than real time only
makes them more lenient.
"""

from __future__ import annotations

import asyncio
import time
from typing import Final, Protocol

__all__ = ["REAL_TIME", "ClientClock", "RealTime"]


class ClientClock(Protocol):
    """A monotonic time line in seconds, and a way to let time pass on it."""

    def now(self) -> float:
        """Monotonic time in seconds (only differences are meaningful)."""
        ...

    async def sleep(self, seconds: float) -> None:
        """Return after ``seconds`` of this clock's time have passed."""
        ...


class RealTime:
    """The wall clock: ``time.monotonic`` and ``asyncio.sleep``."""

    def now(self) -> float:
        return time.monotonic()

    async def sleep(self, seconds: float) -> None:
        await asyncio.sleep(seconds)


REAL_TIME: Final = RealTime()
"""The default clock of every client."""
