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
a line of that kind. :meth:`LogLimiter.close` writes the total that was counted
instead of logged when the source goes away (a client disconnecting).

Time comes from an injected ``now`` (the application's clock in the servers, a fake
one in tests): the limiter never reads the wall clock itself.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Mapping
from typing import Any, Final

__all__ = [
    "LOG_BURST",
    "LOG_SUMMARY_INTERVAL_S",
    "LogLimiter",
    "api_refusal_allowed",
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


def loop_time() -> float:
    """The running event loop's monotonic time: the servers' limiters' clock unless the
    application gives its own (``TcpService.log_clock``)."""
    return asyncio.get_running_loop().time()


class _Kind:
    """The counters of one kind of line from one source."""

    __slots__ = ("last", "level", "logged", "logger", "pending", "since", "total")

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


class LogLimiter:
    """Decides, line by line, whether one source's line is logged or only counted.

    ``prefix`` starts every summary line (``"motion: client 127.0.0.1:5555"``); ``now``
    is a monotonic clock in seconds.
    """

    __slots__ = ("_kinds", "_now", "burst", "interval", "prefix")

    def __init__(
        self,
        prefix: str,
        now: Callable[[], float],
        *,
        burst: int = LOG_BURST,
        interval: float = LOG_SUMMARY_INTERVAL_S,
    ) -> None:
        if burst < 0:
            raise ValueError(f"burst must be >= 0 lines, got {burst}")
        if not interval > 0:
            raise ValueError(f"interval must be > 0 s, got {interval}")
        self.prefix = prefix
        self._now = now
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
        limiter = LogLimiter("control API", loop_time)
        setattr(state, _API_LIMITER, limiter)
    return limiter.allow("refused requests", logger, level)
