"""Controller time, and commands that take some of it.

A MotoROS command that waits (START_TRAJ_MODE polls every 50 ms for up to 5 s …) is
written as a generator that yields how many milliseconds it wants to sleep and
returns its :class:`~pymotoros.controller.api.Outcome`. :meth:`Scheduler.run` starts
it at once: if it finishes without sleeping the caller gets the Outcome; otherwise a
:class:`~pymotoros.controller.api.Pending` that a later :meth:`Scheduler.advance`
(called from ``tick()``) completes.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Generator
from typing import TypeAlias

from pymotoros.controller.values import Outcome, Pending

logger = logging.getLogger(__name__)

Process: TypeAlias = Generator[int, None, Outcome]
"""Yields sleep times in ms, returns the outcome."""


class ControllerClock:
    """Controller time: advanced only by ``VirtualController.tick()``, one period at a time."""

    __slots__ = ("period_ms", "tick_count", "time_ms")

    def __init__(self, period_ms: int) -> None:
        self.period_ms = period_ms
        self.time_ms = 0
        self.tick_count = 0


class _Sleeper:
    __slots__ = ("pending", "process", "wake_ms")

    def __init__(self, process: Process, pending: Pending, wake_ms: int) -> None:
        self.process = process
        self.pending = pending
        self.wake_ms = wake_ms


class Scheduler:
    """Runs processes on the controller clock."""

    __slots__ = ("_clock", "_sleepers", "busy")

    def __init__(self, clock: ControllerClock) -> None:
        self._clock = clock
        self._sleepers: list[_Sleeper] = []
        self.busy = False
        """Some process is waiting (checked every tick)."""

    def run(self, process: Process, describe: Callable[[], str]) -> Outcome | Pending:
        """Start ``process``: its Outcome if it needs no time, else a Pending.

        ``describe()`` names the request; it is called only when a Pending is made.
        """
        try:
            delay = next(process)
        except StopIteration as stop:
            outcome: Outcome = stop.value
            return outcome
        pending = Pending(describe())
        self._sleepers.append(_Sleeper(process, pending, self._clock.time_ms + delay))
        self.busy = True
        return pending

    def advance(self) -> None:
        """Resume every process whose sleep has ended (called once per tick)."""
        if not self._sleepers:
            return
        now = self._clock.time_ms
        for sleeper in list(self._sleepers):
            if now < sleeper.wake_ms:
                continue
            try:
                delay = sleeper.process.send(None)
            except StopIteration as stop:
                self._sleepers.remove(sleeper)
                self.busy = bool(self._sleepers)
                sleeper.pending.complete(stop.value)
                continue
            sleeper.wake_ms = now + delay
