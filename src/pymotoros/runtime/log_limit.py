"""Bounded logging of what clients make the twin say (issue 13: nothing a client sends
can stall the loop).

Every refused frame, refused request and connection is worth a log line, but a buggy
or hostile client sending 100,000 bad frames would write 100,000 lines: with stderr on
a slow pipe or a terminal those writes block the event loop, which also runs the
interpolation ticks, and bury everything else the user needed to see.

A :class:`LogLimiter` counts one source's lines (one client connection, or one port's
connects) by *kind* ("refused frames", "connections" …). The first :data:`LOG_BURST`
lines of a burst are logged as usual; after that they are only counted, and a single
summary line with the count is written at most once per :data:`LOG_SUMMARY_INTERVAL_S`.
A burst ends, and the full allowance comes back, once a whole interval passes without
a line of that kind. A flood that stops is still reported: given a ``schedule`` (the
servers pass :func:`loop_later`), the limiter writes the count one interval after the
first line it counted, even if no other line of that kind ever comes.
:meth:`LogLimiter.close` writes the total that was counted instead of logged when the
source goes away (a client disconnecting).

Time comes from an injected ``now`` (the application's clock in the servers, a fake
one in tests): the limiter never reads the wall clock itself.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Mapping
from typing import Any, Final, Protocol

__all__ = [
    "LOG_BURST",
    "LOG_SUMMARY_INTERVAL_S",
    "LogLimiter",
    "Schedule",
    "api_refusal_allowed",
    "loop_later",
    "loop_time",
]

LOG_BURST: Final = 20
"""Lines of one kind logged in full at the start of a burst, per source: a client's
honest mistakes (a few refused points, a handful of bad frames while a driver is
being written) still show one by one; a flood costs at most this many lines."""

LOG_SUMMARY_INTERVAL_S: Final = 5.0
"""Shortest time between two summary lines of one kind from one source, and the quiet
time that ends a burst: a flood costs one line per 5 s, long enough not to block the
loop on a slow terminal, short enough that an ongoing flood stays visible."""


_API_LIMITER: Final = "pymotoros_refusal_log"
"""Attribute of a control API's ``app.state`` holding its limiter of refusal lines."""


class _Cancellable(Protocol):
    def cancel(self) -> None: ...


Schedule = Callable[[float, Callable[[], None]], _Cancellable]
"""Calls a function after a delay in seconds (``loop.call_later``'s shape): how a limiter
reports a flood that has stopped, with no further line to carry the count."""


def loop_time() -> float:
    """The running event loop's monotonic time: the servers' limiters' clock unless the
    application gives its own (``TcpService.log_clock``)."""
    return asyncio.get_running_loop().time()


def loop_later(delay: float, callback: Callable[[], None]) -> asyncio.TimerHandle:
    """``callback`` after ``delay`` seconds on the running loop: the servers' :data:`Schedule`."""
    return asyncio.get_running_loop().call_later(delay, callback)


class _Kind:
    """The counters of one kind of line from one source."""

    __slots__ = ("last", "level", "logged", "logger", "pending", "since", "timer", "total")

    def __init__(self, logger: logging.Logger, now: float) -> None:
        self.logger = logger
        self.last = now
        """When the previous line of this kind came (logged or not)."""
        self.logged = 0
        """Lines logged in full in the current burst."""
        self.pending = 0
        """Lines counted and not yet reported in a summary."""
        self.since = now
        """When the first of the ``pending`` lines came."""
        self.level = logging.NOTSET
        """The highest level among the lines counted: the level of the summaries."""
        self.total = 0
        """Lines counted instead of logged over the source's life."""
        self.timer: _Cancellable | None = None
        """The scheduled report of the ``pending`` lines, if one is due."""


class LogLimiter:
    """Decides, line by line, whether one source's line is logged or only counted.

    ``prefix`` starts every summary line (``"motion: client 127.0.0.1:5555"``); ``now``
    is a monotonic clock in seconds. With ``schedule``, counted lines are reported one
    interval after the first of them even when no later line comes to carry the count;
    without it (a limiter on its own, in tests), only by the next line or :meth:`close`.
    """

    __slots__ = ("_kinds", "_now", "_schedule", "burst", "interval", "prefix")

    def __init__(
        self,
        prefix: str,
        now: Callable[[], float],
        *,
        burst: int = LOG_BURST,
        interval: float = LOG_SUMMARY_INTERVAL_S,
        schedule: Schedule | None = None,
    ) -> None:
        if burst < 0:
            raise ValueError(f"burst must be >= 0 lines, got {burst}")
        if not interval > 0:
            raise ValueError(f"interval must be > 0 s, got {interval}")
        self.prefix = prefix
        self._now = now
        self._schedule = schedule
        self.burst = burst
        self.interval = interval
        self._kinds: dict[str, _Kind] = {}

    def allow(self, kind: str, logger: logging.Logger, level: int) -> bool:
        """True: log this line of ``kind`` as usual; False: it has been counted instead.

        A line ``logger`` would not emit at ``level`` is neither logged nor counted
        (False): a disabled level costs nothing and is never summarised. May first
        write a summary of the lines counted so far.
        """
        if not logger.isEnabledFor(level):
            return False
        now = self._now()
        k = self._kinds.get(kind)
        if k is None:
            k = self._kinds[kind] = _Kind(logger, now)
            quiet = True
        else:
            quiet = now - k.last >= self.interval
        k.last = now
        if k.pending and (quiet or now - k.since >= self.interval):
            self._summarise(kind, k, now)
        if quiet:
            k.logged = 0  # a new burst: the full allowance again
        if k.logged < self.burst:
            k.logged += 1
            return True
        if not k.pending:
            k.since = now
            if self._schedule is not None and k.timer is None:
                k.timer = self._schedule(self.interval, lambda: self._due(kind))
        k.pending += 1
        k.total += 1
        k.level = max(k.level, level)
        return False

    def suppressed(self, kind: str) -> int:
        """Lines of ``kind`` counted instead of logged so far."""
        k = self._kinds.get(kind)
        return 0 if k is None else k.total

    def close(self) -> None:
        """The source is gone: one line per kind with the total that was not logged."""
        for kind, k in self._kinds.items():
            if k.timer is not None:
                k.timer.cancel()
                k.timer = None
            if not k.total:
                continue
            k.logger.log(
                k.level,
                "%s: %s %s in all were not logged (%s)",
                self.prefix,
                f"{k.total:,}",
                kind,
                self._policy(),
            )
            k.pending = 0
        self._kinds.clear()

    def _due(self, kind: str) -> None:
        """The scheduled report: the lines still pending, once an interval has passed
        since the first of them (else it waits for the rest of the interval)."""
        k = self._kinds.get(kind)
        if k is None:  # closed meanwhile
            return
        k.timer = None
        if not k.pending or self._schedule is None:
            return
        now = self._now()
        wait = k.since + self.interval - now
        if wait > 0:  # the limiter's clock is not the scheduler's (a virtual clock)
            k.timer = self._schedule(wait, lambda: self._due(kind))
            return
        self._summarise(kind, k, now)

    def _summarise(self, kind: str, k: _Kind, now: float) -> None:
        k.logger.log(
            k.level,
            "%s: %s more %s in the last %.1f s (%s)",
            self.prefix,
            f"{k.pending:,}",
            kind,
            now - k.since,
            self._policy(),
        )
        k.pending = 0

    def _policy(self) -> str:
        return (
            f"logging of them is limited: the first {self.burst} of a burst are logged, "
            f"then a count at most every {self.interval:g} s"
        )


def api_refusal_allowed(scope: Mapping[str, Any], logger: logging.Logger, level: int) -> bool:
    """Whether the control API logs one more refused request (:meth:`LogLimiter.allow`).

    HTTP requests have no lasting connection to count by, so each control API (one per
    cell) has one allowance, kept in its ``app.state``: a script hammering it with bad
    requests costs a burst of lines and then a count every few seconds.
    """
    state = getattr(scope.get("app"), "state", None)
    if state is None:  # not inside a Starlette application: nothing to keep it in
        return logger.isEnabledFor(level)
    limiter = getattr(state, _API_LIMITER, None)
    if not isinstance(limiter, LogLimiter):
        limiter = LogLimiter("control API", loop_time, schedule=loop_later)
        setattr(state, _API_LIMITER, limiter)
    return limiter.allow("refused requests", logger, level)
