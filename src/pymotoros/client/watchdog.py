"""Noticing a state stream that stalls while a trajectory is streamed.

On a shop floor the state connection can go silent while the motion port still answers
(a switch dropping one flow, a half-open socket after a laptop slept). A client that
keeps streaming then moves a robot nobody watches. :class:`StallWatchdog` listens to
the state stream and, once nothing arrived for ``bound_s`` (default
:data:`DEFAULT_STATE_STALL_S`, under the 2 s of a dead-stream timeout and 40 state
cycles of MotoROS's 25 ms, §2.3), calls ``on_stall`` once with the silence measured.

Silence is measured on the time line the state stream lives on: the client's
:class:`~pymotoros.client.timing.ClientClock`. Against a robot that is the wall clock
(:data:`~pymotoros.client.timing.REAL_TIME`), and the watchdog is then a single timer
on the event loop's clock, re-armed from the last arrival (one float stored per state
message). In the in-memory twin (:mod:`pymotoros.testing`) it is the twin's virtual
time: the state server writes every 25 ms of *virtual* time, so silence must be
counted in virtual time too, or a pause of the whole process (a debugger, a loaded CI
machine, a GC pause) longer than the bound would trip a move in which the twin was
never silent (issue 31). There the watchdog is a task sleeping on that clock.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Final

from pymotoros.client.motion_port import StateSource
from pymotoros.client.state import RobotState
from pymotoros.client.timing import ClientClock, RealTime

__all__ = ["DEFAULT_STATE_STALL_S", "StallWatchdog"]

DEFAULT_STATE_STALL_S: Final = 1.0
"""Seconds without a state message after which a move is stopped (MotoROS sends ~40 Hz)."""


def _nothing() -> None:
    """A listener already removed."""


class StallWatchdog:
    """Calls ``on_stall(silence_s)`` once when ``states`` is silent for ``bound_s``
    of ``clock``'s time (None or the wall clock: the event loop's timer)."""

    def __init__(
        self,
        states: StateSource,
        bound_s: float,
        on_stall: Callable[[float], None],
        *,
        clock: ClientClock | None = None,
    ) -> None:
        if not bound_s > 0:
            raise ValueError(f"the state stall bound must be > 0 s, got {bound_s!r}")
        self._loop = asyncio.get_running_loop()
        self.bound_s = bound_s
        self._on_stall = on_stall
        self.tripped_after: float | None = None
        """The silence (s) that tripped the watchdog, or None."""
        self._timer: asyncio.TimerHandle | None = None
        self._task: asyncio.Task[None] | None = None
        if clock is None or isinstance(clock, RealTime):
            self._now: Callable[[], float] = self._loop.time
            self._last = self._now()
            self._timer = self._loop.call_at(self._last + bound_s, self._check)
        else:
            self._now = clock.now
            self._last = self._now()
            self._task = self._loop.create_task(
                self._watch(clock), name="pymotoros-state-stall-watchdog"
            )
        self._remove = states.add_listener(self._heard)

    def _heard(self, _state: RobotState) -> None:
        self._last = self._now()

    def _trip(self, silence: float) -> None:
        self.tripped_after = silence
        self._on_stall(silence)

    def _check(self) -> None:
        silence = self._loop.time() - self._last
        if silence >= self.bound_s:
            self._timer = None
            self._trip(silence)
            return
        self._timer = self._loop.call_at(self._last + self.bound_s, self._check)

    async def _watch(self, clock: ClientClock) -> None:
        """The same re-arming check as :meth:`_check`, sleeping on ``clock``."""
        while True:
            await clock.sleep(self._last + self.bound_s - clock.now())
            silence = clock.now() - self._last
            if silence >= self.bound_s:
                self._task = None
                self._trip(silence)
                return

    def close(self) -> None:
        """Stop watching (idempotent)."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        task, self._task = self._task, None
        if task is not None and task is not asyncio.current_task():
            task.cancel()
        remove, self._remove = self._remove, _nothing
        remove()
