"""Log floods (issue 13): what a client makes the twin log is bounded.

The limiter alone on a fake clock, then a running twin fed thousands of refused frames,
refused IO requests and connects, with the limiters' clock replaced by a fake one so
that the bursts and summaries are exact whatever the machine's speed.
"""

from __future__ import annotations

import asyncio
import logging
import re
import struct
from collections.abc import Callable

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.protocol.constants import Port
from pymotoros.protocol.messages import MotoReadIoBit, MotoReadIoBitReply, Ping, PingReply
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.http_api import create_http_app
from pymotoros.runtime.log_limit import (
    _API_LIMITER,
    LOG_BURST,
    LOG_SUMMARY_INTERVAL_S,
    LogLimiter,
)
from pymotoros.runtime.ticker import LatenessStats, TickStats

from .peer import Peer

log = logging.getLogger("test.log_limit")

FLOOD = 2_500
"""Bad frames per batch in the integration tests (two batches: 5,000 in all)."""

UNKNOWN_TYPE = 9999
"""A message type MotoROS does not know: answered INVALID/3003, connection kept (§1.5)."""

BAD_IO_ADDRESS = 99_999_999
"""An IO address outside every range of the IO map: refused with a result code (§6.1)."""


class FakeClock:
    """Monotonic seconds that move only when the test says so."""

    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def lines(caplog: pytest.LogCaptureFixture, pattern: str) -> list[str]:
    return [r.getMessage() for r in caplog.records if re.search(pattern, r.getMessage())]


def counted(message: str) -> int:
    """The count a summary or total line reports ("12,345 more refused frames …")."""
    match = re.search(r": ([\d,]+) (?:more )?\w", message)
    assert match, message
    return int(match.group(1).replace(",", ""))


# ------------------------------------------------------------------ the limiter alone


@pytest.fixture
def fake_clock() -> FakeClock:
    return FakeClock()


def limiter(clock: FakeClock, burst: int = 3, interval: float = 5.0) -> LogLimiter:
    return LogLimiter("motion: client 1.2.3.4:5", clock, burst=burst, interval=interval)


@pytest.fixture
def lim(fake_clock: FakeClock, caplog: pytest.LogCaptureFixture) -> LogLimiter:
    """A limiter (3 a burst, 5 s interval) on the fake clock; its INFO lines captured."""
    caplog.set_level(logging.INFO, logger="test.log_limit")
    return limiter(fake_clock)


def refused_frames(lim: LogLimiter, count: int) -> None:
    """``count`` refused frames offered to ``lim``."""
    for _ in range(count):
        lim.allow("refused frames", log, logging.WARNING)


def test_the_first_lines_of_a_burst_are_logged_then_counted(
    lim: LogLimiter, fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    decisions = [lim.allow("refused frames", log, logging.WARNING) for _ in range(10)]
    assert decisions == [True] * 3 + [False] * 7
    assert lim.suppressed("refused frames") == 7
    assert not caplog.records  # nothing written by the limiter within the interval


def test_a_summary_at_most_once_per_interval_with_the_exact_count(
    lim: LogLimiter, fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    refused_frames(lim, 1_003)  # 3 logged, 1,000 counted, all at once
    fake_clock.t += 1.0
    refused_frames(lim, 500)  # still within the interval of the first counted line
    assert not caplog.records
    fake_clock.t += 4.0  # 5 s after the first counted line, only 1 s after the last one
    assert lim.allow("refused frames", log, logging.WARNING) is False  # still a burst
    [summary] = [r.getMessage() for r in caplog.records]
    assert summary.startswith(
        "motion: client 1.2.3.4:5: 1,500 more refused frames in the last 5.0 s"
    )
    assert "logging of them is limited: the first 3 of a burst are logged" in summary
    assert caplog.records[0].levelno == logging.WARNING  # the level of what it counts


def test_a_quiet_interval_ends_the_burst(
    lim: LogLimiter, fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    refused_frames(lim, 5)
    fake_clock.t += 5.0  # nothing for a whole interval
    assert lim.allow("refused frames", log, logging.WARNING) is True  # a fresh allowance
    [summary] = [r.getMessage() for r in caplog.records]
    assert ": 2 more refused frames in the last 5.0 s" in summary
    assert [lim.allow("refused frames", log, logging.WARNING) for _ in range(3)] == [
        True,
        True,
        False,
    ]
    fake_clock.t += 4.9  # not quiet long enough
    assert lim.allow("refused frames", log, logging.WARNING) is False


def test_kinds_are_counted_separately_and_totals_written_at_close(
    lim: LogLimiter, fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    refused_frames(lim, 8)
    io = [lim.allow("refused IO requests", log, logging.INFO) for _ in range(4)]
    assert io == [True, True, True, False]
    lim.allow("connections", log, logging.INFO)  # one line: nothing to report at close
    lim.close()
    messages = [(r.levelno, r.getMessage()) for r in caplog.records]
    assert len(messages) == 2
    assert messages[0][0] == logging.WARNING
    assert messages[0][1].startswith("motion: client 1.2.3.4:5: 5 refused frames in all were not")
    assert messages[1][0] == logging.INFO
    assert messages[1][1].startswith("motion: client 1.2.3.4:5: 1 refused IO requests in all")


def test_a_disabled_level_is_neither_logged_nor_counted(
    fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING, logger="test.log_limit")
    lim = limiter(fake_clock)
    assert not any(lim.allow("refused IO requests", log, logging.INFO) for _ in range(10))
    assert lim.suppressed("refused IO requests") == 0
    lim.close()
    assert not caplog.records


class FakeScheduler:
    """Collects what a limiter schedules; the test runs the calls when it says so."""

    def __init__(self) -> None:
        self.calls: list[tuple[float, Callable[[], None], FakeTimer]] = []

    def __call__(self, delay: float, callback: Callable[[], None]) -> FakeTimer:
        timer = FakeTimer()
        self.calls.append((delay, callback, timer))
        return timer

    def run_due(self) -> list[float]:
        """Run every scheduled call not cancelled (oldest first); their delays."""
        calls, self.calls = self.calls, []
        delays = []
        for delay, callback, timer in calls:
            if not timer.cancelled:
                delays.append(delay)
                callback()
        return delays


class FakeTimer:
    def __init__(self) -> None:
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


def scheduled_limiter(name: str, clock: FakeClock, burst: int) -> tuple[LogLimiter, FakeScheduler]:
    """A limiter whose delayed reports go to a :class:`FakeScheduler` (returned too)."""
    later = FakeScheduler()
    return LogLimiter(name, clock, burst=burst, schedule=later), later


def test_a_flood_that_stops_is_reported_one_interval_after_its_first_counted_line(
    fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger="test.log_limit")
    lim, later = scheduled_limiter("motion: client 1.2.3.4:5", fake_clock, burst=3)
    refused_frames(lim, 3)  # logged in full: nothing to report, nothing scheduled
    assert later.calls == []
    for _ in range(40):  # counted: one report scheduled, however many are counted
        fake_clock.t += 0.01
        lim.allow("refused frames", log, logging.WARNING)
    assert [delay for delay, _, _ in later.calls] == [5.0]
    fake_clock.t += 5.0  # the flood has stopped: no further line will carry the count
    assert later.run_due() == [5.0]
    [summary] = [r for r in caplog.records]
    assert summary.getMessage().startswith(
        "motion: client 1.2.3.4:5: 40 more refused frames in the last 5.4 s"
    )
    assert summary.levelno == logging.WARNING
    assert later.calls == []  # reported: nothing more is due
    lim.close()  # the total is still written when the client goes
    assert counted(caplog.records[-1].getMessage()) == 40


def test_a_report_on_a_clock_slower_than_the_schedulers_waits_for_the_interval(
    fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    """The limiter's clock may be a virtual one: the report waits for *its* interval."""
    caplog.set_level(logging.INFO, logger="test.log_limit")
    lim, later = scheduled_limiter("io", fake_clock, burst=0)
    lim.allow("connections", log, logging.INFO)
    fake_clock.t += 2.0  # the scheduler's 5 s passed, the limiter's clock only 2 s
    assert later.run_due() == [5.0]
    assert not caplog.records
    assert [delay for delay, _, _ in later.calls] == [3.0]  # the rest of its interval
    fake_clock.t += 3.0
    later.run_due()
    assert [counted(r.getMessage()) for r in caplog.records] == [1]


def test_close_cancels_the_scheduled_report(
    fake_clock: FakeClock, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger="test.log_limit")
    lim, later = scheduled_limiter("io", fake_clock, burst=1)
    for _ in range(5):
        lim.allow("connections", log, logging.INFO)
    lim.close()
    assert [timer.cancelled for _, _, timer in later.calls] == [True]
    assert later.run_due() == []
    [total] = [r.getMessage() for r in caplog.records]
    assert "4 connections in all were not logged" in total


@pytest.mark.parametrize(("burst", "interval"), [(-1, 5.0), (3, 0.0), (3, float("nan"))])
def test_nonsense_settings_are_refused(fake_clock: FakeClock, burst: int, interval: float) -> None:
    with pytest.raises(ValueError, match="must be"):
        LogLimiter("x", fake_clock, burst=burst, interval=interval)


# ------------------------------------------------------------------ a running twin


def unknown_frames(count: int) -> bytes:
    """``count`` well-framed requests of an unknown type (prefix, type, comm, reply code)."""
    return struct.pack("<iiii", 12, UNKNOWN_TYPE, 2, 0) * count


async def served(peer: Peer, count: int) -> None:
    """Wait for ``count`` replies: each was logged (or counted) before it was sent."""
    for _ in range(count):
        await peer.frame()


async def hang_up(app_port_tasks: list[asyncio.Task[None]], peer: Peer) -> None:
    await peer.close()
    done, _ = await asyncio.wait(app_port_tasks, timeout=5.0)
    assert len(done) == len(app_port_tasks), "the server did not notice the client leave"


@pytest.mark.fidelity("safe")  # one write of many frames: safe answers each
async def test_a_flood_of_bad_frames_logs_a_bounded_number_of_lines(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    clock = FakeClock()
    app.motion.log_clock = clock
    caplog.set_level(logging.INFO, logger="pymotoros.runtime")
    peer = await Peer.connect(app.ports.motion, Port.MOTION)
    me = f"127.0.0.1:{peer.writer.get_extra_info('sockname')[1]}"
    await peer.send_raw(unknown_frames(FLOOD))
    await served(peer, FLOOD)
    tasks = list(app.motion._tasks.values())  # its handler has started
    clock.t += LOG_SUMMARY_INTERVAL_S
    await peer.send_raw(unknown_frames(FLOOD))
    await served(peer, FLOOD)
    assert await peer.request(Ping()) == PingReply()  # the client is still served
    await hang_up(tasks, peer)

    mine = re.escape(me)
    refused = lines(caplog, rf"client {mine}: answered INVALID/3003 .*type {UNKNOWN_TYPE}")
    summaries = lines(caplog, rf"client {mine}: [\d,]+ more refused frames")
    totals = lines(caplog, rf"client {mine}: [\d,]+ refused frames in all were not logged")
    # Two bursts (the fake clock jumped a whole interval between them): each logs its
    # first LOG_BURST frames; the first one's count is reported when the second starts.
    assert len(refused) == 2 * LOG_BURST
    assert [counted(s) for s in summaries] == [FLOOD - LOG_BURST]
    assert "in the last 5.0 s" in summaries[0]
    assert [counted(t) for t in totals] == [2 * (FLOOD - LOG_BURST)]
    assert len(lines(caplog, mine)) <= 2 * LOG_BURST + 2 + 2  # + connected, disconnected


async def test_a_flood_of_refused_io_requests_is_bounded_on_both_ports(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    clock = FakeClock()
    app.motion.log_clock = app.io.log_clock = clock
    caplog.set_level(logging.INFO, logger="pymotoros.runtime")
    for tcp_port, port, tasks_of in (
        (app.ports.io, Port.IO, app.io),
        (app.ports.motion, Port.MOTION, app.motion),
    ):
        peer = await Peer.connect(tcp_port, port)
        request = MotoReadIoBit(BAD_IO_ADDRESS)
        reply = await peer.request(request)
        tasks = list(tasks_of._tasks.values())  # its handler has started
        assert isinstance(reply, MotoReadIoBitReply)
        assert reply.result_code != 0
        for _ in range(FLOOD // 50):  # pipelined, 50 at a time
            for _ in range(50):
                await peer.send(request)
            await served(peer, 50)
        await hang_up(tasks, peer)
        name = port.value
        refused = lines(caplog, rf"^{name}: read bit {BAD_IO_ADDRESS} \(value 0\) refused")
        totals = lines(caplog, rf"^{name}: client [\d.:]+: [\d,]+ refused IO requests in all")
        assert len(refused) == LOG_BURST
        assert [counted(t) for t in totals] == [FLOOD + 1 - LOG_BURST]


async def test_a_flood_of_connects_logs_a_bounded_number_of_lines(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    connects = 100
    clock = FakeClock()
    app.io.log_clock = clock
    caplog.set_level(logging.INFO, logger="pymotoros.runtime")
    peers: list[Peer] = []
    for _ in range(connects):  # one IO slot: each newcomer replaces the previous client
        peer = await Peer.connect(app.ports.io, Port.IO)
        await peer.request(MotoReadIoBit(1))  # served: its handler has started
        peers.append(peer)
    assert app.io.replaced == connects - 1
    clock.t += LOG_SUMMARY_INTERVAL_S
    last = await Peer.connect(app.ports.io, Port.IO)
    await last.request(MotoReadIoBit(1))
    assert await last.request(MotoReadIoBit(1)) is not None  # the port still serves
    for peer in [*peers, last]:
        await peer.close()

    connected = lines(caplog, r"^io: client [\d.:]+ connected")
    replaced = lines(caplog, r"^io: [\d.:]+ replaces ")
    assert len(connected) == LOG_BURST + 1  # a burst, then a fresh one after a quiet interval
    assert len(replaced) == LOG_BURST + 1
    [connections] = lines(caplog, r"^io: [\d,]+ more connections in the last 5.0 s")
    [replacements] = lines(caplog, r"^io: [\d,]+ more replaced connections")
    assert counted(connections) == connects - LOG_BURST
    assert counted(replacements) == connects - 1 - LOG_BURST
    # The disconnects of connections that were not logged are not logged either.
    assert len(lines(caplog, r"^io: client [\d.:]+ disconnected")) <= LOG_BURST + 1


async def test_a_flood_of_bad_http_requests_logs_a_bounded_number_of_lines(
    controller: VirtualController, caplog: pytest.LogCaptureFixture
) -> None:
    requests = 300
    clock = FakeClock()
    app = create_http_app(controller, lambda: TickStats(4.0, 0, 0, 0, 0, LatenessStats(0, 0, 0)))
    setattr(app.state, _API_LIMITER, LogLimiter("control API", clock))
    caplog.set_level(logging.INFO, logger="pymotoros.runtime")
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://sim") as api:
        for index in range(requests):
            kind = index % 3  # malformed JSON, a refused value, a repeated key
            body = [b"{not json", b'{"address": -1, "value": 1}', b'{"on": true, "on": true}']
            path = "/api/io" if kind == 1 else "/api/hold"
            r = await api.post(
                path, content=body[kind], headers={"content-type": "application/json"}
            )
            assert r.status_code == 422
        clock.t += LOG_SUMMARY_INTERVAL_S
        assert (await api.post("/api/hold", content=b"{")).status_code == 422
        assert (await api.post("/api/hold", json={"on": True})).status_code == 200

    refused = lines(caplog, r"^control API refused a request: ")
    [summary] = lines(caplog, r"^control API: [\d,]+ more refused requests in the last 5.0 s")
    assert len(refused) == LOG_BURST + 1  # a burst, then a fresh one after a quiet interval
    assert counted(summary) == requests - LOG_BURST


@pytest.mark.fidelity("safe")  # one write of many frames: safe answers each
async def test_each_ports_refusals_and_their_counts_are_logged_under_its_own_logger(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    """The motion port shares the IO and frame checks with the IO port, but a user
    filtering logs by logger sees each port's lines (and their summaries) under its name."""
    caplog.set_level(logging.INFO, logger="pymotoros.runtime")
    for tcp_port, port, server in (
        (app.ports.motion, Port.MOTION, app.motion),
        (app.ports.io, Port.IO, app.io),
    ):
        caplog.clear()
        peer = await Peer.connect(tcp_port, port)
        assert isinstance(await peer.request(MotoReadIoBit(BAD_IO_ADDRESS)), MotoReadIoBitReply)
        tasks = list(server._tasks.values())  # its handler has started
        flood = LOG_BURST + 7
        await peer.send_raw(unknown_frames(flood))
        await served(peer, flood)
        for _ in range(flood):
            await peer.send(MotoReadIoBit(BAD_IO_ADDRESS))
        await served(peer, flood)
        await hang_up(tasks, peer)
        name = f"pymotoros.runtime.{'motion_server' if port is Port.MOTION else 'io_server'}"
        about = [
            r
            for r in caplog.records
            if re.search(r"INVALID/3003|refused|were not logged", r.getMessage())
        ]
        # 20 frames + 20 IO refusals in full, then one total per kind at disconnect
        assert len(about) == 2 * LOG_BURST + 2, [r.getMessage() for r in about]
        assert {r.name for r in about} == {name}


@pytest.mark.fidelity("safe")  # one write of many frames: safe answers each
async def test_a_flood_that_stops_is_reported_while_the_client_stays_connected(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.INFO, logger="pymotoros.runtime")
    peer = await Peer.connect(app.ports.motion, Port.MOTION)
    assert await peer.request(Ping()) == PingReply()
    [conn] = app.motion._tasks  # its handler has started
    conn.log.interval = 0.05  # a short interval: the test waits for it in real time
    await peer.send_raw(unknown_frames(LOG_BURST + 30))
    await served(peer, LOG_BURST + 30)
    summaries: list[logging.LogRecord] = []
    # Bounded in loop turns, not wall time: the report's 50 ms timer and these 10 ms
    # polls run on the same event loop, so a loaded machine delays both alike and the
    # report is always due within the first few polls (docs/testing.md).
    for _ in range(200):
        summaries = [r for r in caplog.records if "more refused frames" in r.getMessage()]
        if summaries:
            break
        await asyncio.sleep(0.01)
    assert [counted(r.getMessage()) for r in summaries] == [30]
    assert summaries[0].name == "pymotoros.runtime.motion_server"
    assert await peer.request(Ping()) == PingReply()  # still connected and served
    await peer.close()
