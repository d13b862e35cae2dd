"""Noticing a state stream that stalls while a trajectory is streamed.

On a shop floor the state connection can go silent while the motion port still answers
(a switch dropping one flow, a half-open socket after a laptop slept). A client that
keeps streaming then moves a robot nobody watches. :class:`StallWatchdog` listens to
the state stream and, once nothing arrived for ``bound_s`` (default
:data:`DEFAULT_STATE_STALL_S`, under the 2 s of a dead-stream timeout and 40 state
cycles of MotoROS's 25 ms, §2.3), calls ``on_stall`` once with the silence measured.

It is a single timer on the event loop's clock; the state listener only stores the
arrival time (one float per message), and the timer re-arms itself from it.
Like the client's request timeouts, it runs on the loop's clock, not the injectable
:class:`~pymotoros.client.timing.ClientClock` (a twin in virtual time only sends state
faster, which never trips it).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Final

from pymotoros.client.motion_port import StateSource
from pymotoros.client.state import RobotState

__all__ = ["DEFAULT_STATE_STALL_S", "StallWatchdog"]

DEFAULT_STATE_STALL_S: Final = 1.0
"""Seconds without a state message after which a move is stopped (MotoROS sends ~40 Hz)."""


def _nothing() -> None:
    """A listener already removed."""


class StallWatchdog:
    """Calls ``on_stall(silence_s)`` once when ``states`` is silent for ``bound_s``."""

    def __init__(
        self,
        states: StateSource,
        bound_s: float,
        on_stall: Callable[[float], None],
    ) -> None:
        if not bound_s > 0:
            raise ValueError(f"the state stall bound must be > 0 s, got {bound_s!r}")
        self._loop = asyncio.get_running_loop()
        self.bound_s = bound_s
        self._on_stall = on_stall
        self._last = self._loop.time()
        self.tripped_after: float | None = None
        """The silence (s) that tripped the watchdog, or None."""
        self._remove = states.add_listener(self._heard)
        self._timer: asyncio.TimerHandle | None = self._loop.call_at(
            self._last + bound_s, self._check
        )

    def _heard(self, _state: RobotState) -> None:
        self._last = self._loop.time()

    def _check(self) -> None:
        silence = self._loop.time() - self._last
        if silence >= self.bound_s:
            self._timer = None
            self.tripped_after = silence
            self._on_stall(silence)
            return
        self._timer = self._loop.call_at(self._last + self.bound_s, self._check)

    def close(self) -> None:
        """Stop watching (idempotent)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        remove, self._remove = self._remove, _nothing
        remove()
