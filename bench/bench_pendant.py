"""The web pendant's cost to the interpolation loop (prints numbers; not a test).

    python bench/bench_pendant.py                            # the recorded run
    python bench/bench_pendant.py --duration 10 --rounds 2   # a quick look

Issue 12, item 3: the loop's lateness p99 while a trajectory streams, with three pendant
tabs open, next to the same run without them. Each round runs both, each against a fresh
``pymotoros sim`` subprocess (``bench_runtime.stream_and_listen``: a JOINT_TRAJ_PT_FULL
sweep with BUSY retries plus four state clients, lateness read from the control API
after a warm-up and ``POST /api/tick/reset``), in alternating order (none first in odd
rounds, tabs first in even ones) so that a machine getting busier or quieter during the
run does not favour either side.

This machine's noise (other jobs, a VM whose virtual CPUs are descheduled) moves a run's
p99 by more than the effect being measured, so the verdict is the median of the
per-round ratios (tabs / none, the two runs of a round measured minutes apart), printed
with their spread, next to the ratio of the medians. Each run also prints the
simulator's CPU use (its own cost, steadier than lateness) and the load average.

A "tab" is what the simulator serves to one open pendant: the page and its assets once,
then the ``/ws/state`` WebSocket feed, read in full at the rate it is pushed. The three
tabs run in one separate, lightweight process (one asyncio task each, the WebSocket
protocol done by ``wsproto``, the library uvicorn uses on the simulator's side; no
threads), so that on this 2-core machine the readers take as little CPU as a browser's
network process would; its CPU use is printed too. ``--browser`` opens three real tabs
in headless Chromium instead (Selenium + chromedriver from Debian), which adds the
browser's own rendering to the machine's load.
"""

from __future__ import annotations

import argparse
import asyncio
import bisect
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import READY, Sim, running_sim, stop_sim, stream_and_listen

TABS = 3
"""The issue's number of pendant tabs."""
MIN_PHASE_SAMPLES = 20
"""Phases with fewer ticks (the odd one at a resync) are not worth a line."""

TAB_PROCESS = textwrap.dedent(
    """
    import asyncio, sys, time, urllib.request
    from wsproto import ConnectionType, WSConnection
    from wsproto.events import AcceptConnection, CloseConnection, Ping, Request, TextMessage

    port, tabs = int(sys.argv[1]), int(sys.argv[2])
    base = f"http://127.0.0.1:{port}"

    async def tab(counts, i):
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        ws = WSConnection(ConnectionType.CLIENT)
        writer.write(ws.send(Request(host=f"127.0.0.1:{port}", target="/ws/state",
                                     extra_headers=[(b"origin", base.encode())])))
        while data := await reader.read(65536):
            ws.receive_data(data)
            for event in ws.events():
                if isinstance(event, TextMessage) and event.message_finished:
                    counts[i] += 1
                elif isinstance(event, Ping):  # uvicorn's keep-alive, every 20 s
                    writer.write(ws.send(event.response()))
                elif isinstance(event, CloseConnection):
                    raise SystemExit(f"tab {i}: the simulator closed the feed")
                elif not isinstance(event, (AcceptConnection, TextMessage)):
                    raise SystemExit(f"tab {i}: unexpected {event!r}")

    async def main():
        for _ in range(tabs):  # each tab loads the page and its assets once
            for path in ("/", "/pendant/pendant.js", "/pendant/pendant.css"):
                urllib.request.urlopen(base + path, timeout=10).read()
        counts = [0] * tabs
        tasks = [asyncio.create_task(tab(counts, i)) for i in range(tabs)]
        t0 = time.monotonic()
        stop = asyncio.ensure_future(asyncio.to_thread(sys.stdin.readline))  # when to stop
        done, _ = await asyncio.wait([stop, *tasks], return_when=asyncio.FIRST_COMPLETED)
        elapsed = time.monotonic() - t0
        for t in tasks:
            if t in done:
                t.result()  # a tab's failure ends the process with its message
                raise SystemExit("a tab's feed ended early")
            t.cancel()
        cpu = time.process_time()
        print(" ".join(f"{c / elapsed:.1f}" for c in counts), f"{cpu / elapsed:.4f}", flush=True)

    asyncio.run(main())
    """
)


TRACED_SIM = textwrap.dedent(
    """
    import atexit, gc, json, sys, time
    from pymotoros.runtime import pendant, ticker

    out, argv = sys.argv[1], sys.argv[2:]
    ticks, collections, captures, started = [], [], [], [0.0]

    def on_gc(phase, info):
        if phase == "start":
            started[0] = time.monotonic()
        else:
            collections.append((started[0], time.monotonic() - started[0], info["generation"]))

    gc.callbacks.append(on_gc)
    init = ticker.Ticker.__init__

    def traced_init(self, step, period, clock, **kw):
        def traced_step():  # the lateness the ticker has just recorded for this tick
            late = float(self._lateness[(self._samples - 1) % len(self._lateness)])
            ticks.append((time.monotonic(), late))
            step()
        init(self, traced_step, period, clock, **kw)

    ticker.Ticker.__init__ = traced_init
    capture = pendant.PendantDocument.capture

    def traced_capture(self):
        captures.append(time.monotonic())
        return capture(self)

    pendant.PendantDocument.capture = traced_capture
    costs = {}  # piece of the feed's work -> [calls, CPU seconds]

    def costed(name, f):  # the process's CPU time, not wall time: preemption excluded
        def timed(*args):
            c0 = time.process_time()
            try:
                return f(*args)
            finally:
                cost = costs.setdefault(name, [0, 0.0])
                cost[0] += 1
                cost[1] += time.process_time() - c0
        return timed

    def costed_async(name, f):
        async def timed(*args):
            c0 = time.process_time()
            try:
                return await f(*args)
            finally:
                cost = costs.setdefault(name, [0, 0.0])
                cost[0] += 1
                cost[1] += time.process_time() - c0
        return timed

    from pymotoros.controller import VirtualController
    from starlette.websockets import WebSocket
    pendant.PendantDocument.capture = costed("capture", pendant.PendantDocument.capture)
    VirtualController.snapshot = costed("  of which snapshot", VirtualController.snapshot)
    pendant.PendantDocument.render = costed("render", pendant.PendantDocument.render)
    pendant.encode = costed("encode", pendant.encode)
    WebSocket.send_text = costed_async("send to one tab", WebSocket.send_text)

    def dump():
        with open(out, "w") as f:
            json.dump({"ticks": ticks, "gc": collections, "captures": captures,
                       "costs": costs}, f)

    atexit.register(dump)
    from pymotoros.cli.main import main
    sys.argv = ["pymotoros", *argv]
    main()
    """
)


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far (Linux /proc)."""
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@contextlib.contextmanager
def websocket_tabs(sim: Sim, nice: int = 0) -> Iterator[list[float]]:
    """Three pendant feeds in another process; yields a list filled with each tab's Hz,
    then the tab process's CPU use (share of one core)."""
    rates: list[float] = []
    cmd = [sys.executable, "-c", TAB_PROCESS, str(sim.http), str(TABS)]
    if nice:
        cmd = ["nice", "-n", str(nice), *cmd]
    proc = subprocess.Popen(  # noqa: S603 - our own argv
        cmd,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        yield rates
    finally:
        out, _ = proc.communicate("stop\n", timeout=30)
        if proc.returncode != 0:
            raise SystemExit(f"the tabs' process failed ({proc.returncode}): {out!r}")
        rates.extend(float(x) for x in out.split())


@contextlib.contextmanager
def browser_tabs(sim: Sim) -> Iterator[list[float]]:
    """Three real tabs in headless Chromium; yields a list filled with each tab's Hz."""
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"):
        options.add_argument(arg)
    driver = webdriver.Chrome(options=options, service=Service("/usr/bin/chromedriver"))
    rates: list[float] = []
    url = f"http://127.0.0.1:{sim.http}/"
    try:
        handles = []
        for i in range(TABS):
            if i:
                driver.switch_to.new_window("tab")
            driver.get(url)
            handles.append(driver.current_window_handle)
        starts = []
        for h in handles:
            driver.switch_to.window(h)
            starts.append(
                (time.monotonic(), driver.execute_script("return window.pendant.updates"))
            )
        yield rates
        for h, (t0, n0) in zip(handles, starts, strict=True):
            driver.switch_to.window(h)
            n1 = driver.execute_script("return window.pendant.updates")
            rates.append((n1 - n0) / (time.monotonic() - t0))
    finally:
        driver.quit()


def one_run(
    duration: float, warmup: float, tabs: str, nice: int = 0, fifo: int = 0
) -> dict[str, Any]:
    with running_sim(fifo=fifo) as sim:
        cpu0, t0 = cpu_seconds(sim.proc.pid), time.monotonic()
        tab_cpu: float | None = None
        if tabs == "none":
            result = asyncio.run(stream_and_listen(sim, duration, warmup))
            rates: list[float] = []
        else:
            opener = browser_tabs(sim) if tabs == "browser" else websocket_tabs(sim, nice)
            with opener as rates:
                result = asyncio.run(stream_and_listen(sim, duration, warmup))
            if tabs != "browser":
                tab_cpu, rates = rates[-1], rates[:-1]
        result["sim_cpu"] = (cpu_seconds(sim.proc.pid) - cpu0) / (time.monotonic() - t0)
        result["tab_hz"] = rates
        result["tab_cpu"] = tab_cpu
        return result


def phases(duration: float, warmup: float) -> None:
    """Where the late ticks are, in one run with tabs: lateness by the tick's place in
    the feed's 10-tick period (1 = the first tick after the feed captured the state),
    and the garbage collector's pauses. A feed that delays the loop shows as phases
    later than the others; the machine's own noise is the same in every phase."""
    with tempfile.TemporaryDirectory() as tmp:
        trace = Path(tmp) / "trace.json"
        argv = ["-q", "sim", "--motion-port", "0", "--state-port", "0", "--io-port", "0"]
        cmd = [sys.executable, "-c", TRACED_SIM, str(trace), *argv, "--http-port", "0"]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)  # noqa: S603
        assert proc.stdout is not None
        match = READY.fullmatch(proc.stdout.readline().strip())
        if match is None:
            proc.kill()
            raise SystemExit("the traced simulator did not start")
        motion, state, io, http = (int(g) for g in match.groups())
        sim = Sim(proc, motion, state, io, http, startup_s=0.0)
        try:
            with websocket_tabs(sim):
                asyncio.run(stream_and_listen(sim, duration, warmup))
        finally:
            stop_sim(sim)
        data = json.loads(trace.read_text())
    captures = data["captures"]
    times = [t for t, _ in data["ticks"]]
    late = [1000.0 * x for _, x in data["ticks"]]
    first = bisect.bisect_left(times, times[-1] - duration)  # the measured stretch
    by_phase: dict[int, list[float]] = {}
    for i in range(first, len(times)):
        c = bisect.bisect_left(captures, times[i]) - 1  # the last capture before tick i
        if c < 0:
            continue
        phase = i - bisect.bisect_right(times, captures[c]) + 1
        by_phase.setdefault(phase, []).append(late[i])
    print(f"lateness (ms) by phase in the feed's period, {duration:.0f} s with {TABS} tabs:")
    for phase in sorted(by_phase):
        v = sorted(by_phase[phase])
        if len(v) < MIN_PHASE_SAMPLES:
            continue
        print(
            f"  phase {phase:2d}: n {len(v):5d} mean {statistics.fmean(v):.3f} "
            f"p90 {v[int(0.9 * len(v))]:.3f} p99 {v[int(0.99 * len(v))]:.3f}"
        )
    print("the feed's work on the loop, CPU µs per call (process time, whole run):")
    for name, (calls, seconds) in data["costs"].items():
        print(f"  {name:20s} {1e6 * seconds / max(1, calls):7.1f} ({calls} calls)")
    start = times[first]
    pauses = [(t, d * 1000.0, g) for t, d, g in data["gc"] if t >= start]
    worst = sorted(range(first, len(times)), key=lambda i: late[i])[-max(1, len(late) // 100) :]
    near = sum(1 for i in worst if any(times[i - 1] <= t <= times[i] for t, _, _ in pauses))
    print(
        f"garbage collections: {len(pauses)} "
        f"(by generation {[sum(1 for p in pauses if p[2] == g) for g in range(3)]}), "
        f"longest {max((d for _, d, _ in pauses), default=0.0):.2f} ms; "
        f"{near} of the {len(worst)} latest ticks had a collection just before"
    )


def pct(shares: list[float]) -> float:
    return round(100 * statistics.median(shares), 1)


def spread(values: list[float]) -> str:
    return f"{min(values):.2f}–{max(values):.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=30.0, help="measured seconds per run")
    parser.add_argument("--warmup", type=float, default=3.0, help="seconds before measuring")
    parser.add_argument("--rounds", type=int, default=6, help="rounds of both runs")
    parser.add_argument("--browser", action="store_true", help="real Chromium tabs")
    parser.add_argument(
        "--tab-nice",
        type=int,
        default=0,
        help="run the WebSocket tabs under nice N: tells the simulator's own cost from "
        "the CPU the tabs' process takes from it on a 2-core machine",
    )
    parser.add_argument(
        "--sim-fifo",
        type=int,
        default=0,
        help="run the simulator under `chrt --fifo N` (SCHED_FIFO, as `pymotoros sim "
        "--realtime` asks for) in both runs: the scheduler then cannot delay a tick "
        "for the CPU the feed used just before it",
    )
    parser.add_argument(
        "--phases",
        action="store_true",
        help="instead: one traced run with tabs; lateness by place in the feed's period, "
        "the CPU each piece of the feed's work takes on the loop, and the garbage "
        "collector's pauses (where the tabs' cost comes from)",
    )
    args = parser.parse_args()
    if args.rounds < 1 or args.duration <= 0:
        parser.error("--rounds must be at least 1 and --duration positive")
    if args.phases:
        phases(args.duration, args.warmup)
        return
    kind = "browser" if args.browser else "websocket"
    p99: dict[str, list[float]] = {"none": [], kind: []}
    cpu: dict[str, list[float]] = {"none": [], kind: []}
    ratios: list[float] = []
    print(f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}", flush=True)
    for r in range(args.rounds):
        order = ("none", kind) if r % 2 == 0 else (kind, "none")
        this_round: dict[str, float] = {}
        for tabs in order:
            res = one_run(args.duration, args.warmup, tabs, args.tab_nice, args.sim_fifo)
            tick = res["tick"]
            late = tick["lateness_ms"]
            p99[tabs].append(late["p99"])
            cpu[tabs].append(res["sim_cpu"])
            this_round[tabs] = late["p99"]
            hz = ", ".join(f"{x:.1f}" for x in res["tab_hz"])
            extra = f", tab Hz [{hz}]" if hz else ""
            if res["tab_cpu"] is not None:
                extra += f", tab process CPU {100 * res['tab_cpu']:.1f} %"
            print(
                f"round {r + 1} tabs={tabs:9s} p50 {late['p50']:.3f} p99 {late['p99']:.3f} "
                f"max {late['max']:.2f} ms, overruns {tick['overruns']} of {tick['count']} "
                f"ticks, points {res['points']}, sim CPU {100 * res['sim_cpu']:.1f} %{extra}, "
                f"load {os.getloadavg()[0]:.2f}",
                flush=True,
            )
        if this_round["none"] > 0:
            ratios.append(this_round[kind] / this_round["none"])
            print(f"round {r + 1} ratio {ratios[-1]:.2f}", flush=True)
    base = statistics.median(p99["none"])
    with_tabs = statistics.median(p99[kind])
    print(f"load average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(
        json.dumps(
            {
                "rounds": args.rounds,
                "median_p99_ms_without_tabs": round(base, 3),
                f"median_p99_ms_with_{TABS}_{kind}_tabs": round(with_tabs, 3),
                "ratio_of_medians": round(with_tabs / base, 2) if base else None,
                "median_of_round_ratios": round(statistics.median(ratios), 2) if ratios else None,
                "round_ratios_spread": spread(ratios) if ratios else None,
                "p99_spread_ms_without_tabs": spread(p99["none"]),
                f"p99_spread_ms_with_{kind}_tabs": spread(p99[kind]),
                "median_sim_cpu_pct_without_tabs": pct(cpu["none"]),
                f"median_sim_cpu_pct_with_{kind}_tabs": pct(cpu[kind]),
            }
        )
    )


if __name__ == "__main__":
    main()
