"""``GET /metrics``: the twin in the Prometheus text format (prometheus-client).

Operators who run many twins (a CI farm, a fleet in a cluster) scrape them like any
service. Nothing here runs on the hot path: the interpolation loop, the servers and the
controller keep counting in plain ints (``Ticker.count``/``overruns``, its lateness
ring, :class:`~pymotoros.runtime.traffic.Traffic`, the PFL and FSU counters), and a
custom collector turns them into metric families when somebody scrapes. A twin nobody
scrapes pays nothing for this module.

Exported (every family carries a ``cell`` label when the process runs several cells,
``pymotoros sim --config a.toml --config b.toml``; the loop families are the process's
shared loop, the same on every cell):

* ``pymotoros_ticks_total``: interpolation ticks the controller ran;
* ``pymotoros_loop_lateness_seconds`` (histogram): how late each tick started;
  ``pymotoros_loop_lateness_unsampled_total``: ticks whose lateness was overwritten in
  the loop's ring before a scrape read it (scrape more often than every 60 s);
* ``pymotoros_loop_overruns_total``, ``pymotoros_loop_skipped_ticks_total``;
* ``pymotoros_connections{port}``: clients connected now on motion, state and IO;
* ``pymotoros_requests_total{port,type}``: requests decoded, by message type;
* ``pymotoros_replies_total{port,subject,result}``: replies sent, by what they answer
  (the MOTION_CTRL command or request type) and result code;
* ``pymotoros_refusals_total{port,result,subcode}``: non-zero results (BUSY included);
* ``pymotoros_alarms_total``, ``pymotoros_alarms_active``;
* ``pymotoros_pfl_events_total`` (contacts and clampings), ``pymotoros_fsu_switches_total``.

The endpoint is open, like the MotoROS ports, unless the control API has a token
(``pymotoros sim --token``): then it takes the same ``Authorization: Bearer`` header
(runtime/access.py), so a Prometheus scrape config names the token too (docs/sim.md).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Final, Protocol

import numpy as np
from fastapi import FastAPI
from fastapi.responses import Response
from prometheus_client import CONTENT_TYPE_LATEST, CollectorRegistry, generate_latest
from prometheus_client.core import (
    CounterMetricFamily,
    GaugeMetricFamily,
    HistogramMetricFamily,
    Metric,
)
from prometheus_client.registry import Collector

from pymotoros.protocol.constants import MotionCommand, MsgType
from pymotoros.runtime.target import SimulatedController
from pymotoros.runtime.ticker import Ticker
from pymotoros.runtime.traffic import OTHER, Traffic

__all__ = ["LATENESS_BUCKETS_S", "TwinCollector", "install_metrics"]

LATENESS_BUCKETS_S: Final = (
    0.0001,
    0.00025,
    0.0005,
    0.001,
    0.002,
    0.004,
    0.008,
    0.016,
    0.032,
    0.064,
    0.128,
)
"""Upper bounds of the lateness histogram: 0.1 ms (a quiet machine) to 32 periods."""


def _type_name(value: int) -> str:
    if value == OTHER:
        return "other"
    for enum in (MotionCommand, MsgType):
        try:
            return str(enum(value).name)
        except ValueError:
            continue
    return str(value)


class _Monotonic:
    """A counter read from a source that :meth:`Ticker.reset_stats` may set back to 0."""

    __slots__ = ("_last", "total")

    def __init__(self) -> None:
        self.total = 0
        self._last = 0

    def update(self, value: int) -> int:
        self.total += value - self._last if value >= self._last else value
        self._last = value
        return self.total


class CountedPort(Protocol):
    """A MotoROS port's server as the collector reads it: its traffic counters."""

    @property
    def traffic(self) -> Traffic: ...


class MetricsSource(Protocol):
    """What the collector reads of one simulator at scrape time (runtime/app.py's
    ``SimulatorApp`` is one): declared here, so the app imports this module and not the
    other way round."""

    @property
    def controller(self) -> SimulatedController: ...

    @property
    def ticker(self) -> Ticker: ...

    @property
    def motion(self) -> CountedPort: ...

    @property
    def io(self) -> CountedPort: ...

    @property
    def metrics_cell(self) -> str | None:
        """The ``cell`` label (None: a process of one cell, no label)."""

    def client_counts(self) -> dict[str, int]: ...


class TwinCollector(Collector):
    """Reads one simulator's counters at scrape time."""

    def __init__(self, app: MetricsSource, cell: str | None = None) -> None:
        self._app = app
        self._cell = cell
        self._mark = 0
        self._buckets = np.zeros(len(LATENESS_BUCKETS_S) + 1, dtype=np.int64)
        self._bounds = np.array(LATENESS_BUCKETS_S)
        self._sum = 0.0
        self._unsampled = 0
        self._overruns = _Monotonic()
        self._skipped = _Monotonic()

    @property
    def cell(self) -> str | None:
        return self._cell if self._cell is not None else self._app.metrics_cell

    def _labels(self, *names: str) -> list[str]:
        return ["cell", *names] if self.cell is not None else list(names)

    def _values(self, *values: str) -> list[str]:
        cell = self.cell
        return [cell, *values] if cell is not None else list(values)

    def collect(self) -> Iterator[Metric]:
        app = self._app
        controller = app.controller
        labels, values = self._labels, self._values

        ticks = CounterMetricFamily(
            "pymotoros_ticks", "Interpolation ticks the controller ran.", labels=labels()
        )
        # The controller's own count, from its snapshot (the runtime's one view of it).
        ticks.add_metric(values(), float(controller.snapshot().tick_count))
        yield ticks

        yield from self._loop_families()

        conns = GaugeMetricFamily(
            "pymotoros_connections",
            "Clients connected now, per MotoROS port.",
            labels=labels("port"),
        )
        for port, count in app.client_counts().items():
            conns.add_metric(values(port), float(count))
        yield conns

        requests = CounterMetricFamily(
            "pymotoros_requests",
            "Requests decoded, by port and message type.",
            labels=labels("port", "type"),
        )
        replies = CounterMetricFamily(
            "pymotoros_replies",
            "Replies sent, by port, what they answer and result code.",
            labels=labels("port", "subject", "result"),
        )
        refusals = CounterMetricFamily(
            "pymotoros_refusals",
            "Replies with a non-zero result (BUSY included), by port, result and subcode.",
            labels=labels("port", "result", "subcode"),
        )
        for port, server in (("motion", app.motion), ("io", app.io)):
            traffic = server.traffic
            for msg_type, n in list(traffic.requests.items()):
                requests.add_metric(values(port, _type_name(msg_type)), float(n))
            for (subject, result), n in list(traffic.replies.items()):
                replies.add_metric(values(port, _type_name(subject), str(result)), float(n))
            for (result, subcode), n in list(traffic.refusals.items()):
                refusals.add_metric(values(port, str(result), str(subcode)), float(n))
        yield requests
        yield replies
        yield refusals

        yield from self._safety_families()

    def _loop_families(self) -> Iterator[Metric]:
        labels, values = self._labels, self._values
        ticker = self._app.ticker
        samples, self._mark, lost = ticker.lateness_since(self._mark)
        if len(samples):
            index = np.searchsorted(self._bounds, samples, side="left")
            self._buckets += np.bincount(index, minlength=len(self._buckets))
            self._sum += float(samples.sum())
        self._unsampled += lost
        cumulative = np.cumsum(self._buckets)
        histogram = HistogramMetricFamily(
            "pymotoros_loop_lateness_seconds",
            "How late each interpolation tick started (seconds).",
            labels=labels(),
        )
        buckets = [
            (repr(b), float(c)) for b, c in zip(LATENESS_BUCKETS_S, cumulative, strict=False)
        ]
        buckets.append(("+Inf", float(cumulative[-1])))
        histogram.add_metric(values(), buckets, self._sum)
        yield histogram
        unsampled = CounterMetricFamily(
            "pymotoros_loop_lateness_unsampled",
            "Ticks whose lateness left the loop's ring before a scrape read it.",
            labels=labels(),
        )
        unsampled.add_metric(values(), float(self._unsampled))
        yield unsampled
        overruns = CounterMetricFamily(
            "pymotoros_loop_overruns",
            "Ticks that started more than one period late.",
            labels=labels(),
        )
        overruns.add_metric(values(), float(self._overruns.update(ticker.overruns)))
        yield overruns
        skipped = CounterMetricFamily(
            "pymotoros_loop_skipped_ticks",
            "Ticks skipped after a stall of the loop (the twin's time then lags wall time).",
            labels=labels(),
        )
        skipped.add_metric(values(), float(self._skipped.update(ticker.skipped)))
        yield skipped

    def _safety_families(self) -> Iterator[Metric]:
        labels, values = self._labels, self._values
        controller = self._app.controller
        snapshot = controller.snapshot()
        active = GaugeMetricFamily("pymotoros_alarms_active", "Alarms active now.", labels=labels())
        active.add_metric(values(), float(len(snapshot.alarms)))
        yield active
        total = CounterMetricFamily(
            "pymotoros_alarms", "Alarms and operator errors raised.", labels=labels()
        )
        # counted by the controller as each is raised (its history keeps only the last 100)
        total.add_metric(values(), float(controller.alarms_raised()))
        yield total
        safety = controller.safety
        pfl = CounterMetricFamily(
            "pymotoros_pfl_events", "PFL contacts and clampings since boot.", labels=labels()
        )
        pfl.add_metric(values(), float(safety.pfl.status.events))
        yield pfl
        fsu = CounterMetricFamily(
            "pymotoros_fsu_switches", "FSU limit switches at run time.", labels=labels()
        )
        fsu.add_metric(values(), float(safety.fsu.switches))
        yield fsu


def install_metrics(api: FastAPI, app: MetricsSource) -> CollectorRegistry:
    """Serve ``GET /metrics`` for ``app`` on its control API; returns the registry."""
    registry = CollectorRegistry(auto_describe=False)
    registry.register(TwinCollector(app))

    @api.get("/metrics", include_in_schema=False)
    async def metrics() -> Response:
        """The twin's counters in the Prometheus text format."""
        return Response(generate_latest(registry), media_type=CONTENT_TYPE_LATEST)

    return registry
