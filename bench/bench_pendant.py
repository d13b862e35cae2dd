"""The web pendant's cost to the interpolation loop (prints numbers; not a test).

    python bench/bench_pendant.py                      # the recorded run
    python bench/bench_pendant.py --duration 10 --rounds 1   # a quick look

Issue 12, item 3: the loop's lateness p99 while a trajectory streams, with three pendant
tabs open, next to the same run without them. Each round runs both, alternately, each
against a fresh ``pymotoros sim`` subprocess (``bench_runtime.stream_and_listen``: a
JOINT_TRAJ_PT_FULL sweep with BUSY retries plus four state clients, lateness read from the
control API after a warm-up and ``POST /api/tick/reset``).

A "tab" is what the simulator serves to one open pendant: the page and its assets once,
then the ``/ws/state`` WebSocket feed, read in full at the rate it is pushed. The three
tabs run in a separate process (``websocket-client`` threads), so the numbers are the
simulator's cost. ``--browser`` opens three real tabs in headless Chromium instead
(Selenium + chromedriver from Debian), which adds the browser's own rendering to the
machine's load: on a 2-core machine that competes with the loop for the CPU.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import Sim, running_sim, stream_and_listen

TABS = 3
"""The issue's number of pendant tabs."""

TAB_PROCESS = textwrap.dedent(
    """
    import sys, threading, time, urllib.request
    import websocket

    port, tabs = int(sys.argv[1]), int(sys.argv[2])
    base = f"http://127.0.0.1:{port}"
    counts = [0] * tabs
    stop = threading.Event()

    def tab(i):
        for path in ("/", "/pendant/pendant.js", "/pendant/pendant.css"):
            urllib.request.urlopen(base + path, timeout=10).read()
        ws = websocket.create_connection(f"ws://127.0.0.1:{port}/ws/state", timeout=10,
                                         origin=base)
        while not stop.is_set():
            ws.recv()
            counts[i] += 1
        ws.close()

    threads = [threading.Thread(target=tab, args=(i,)) for i in range(tabs)]
    for t in threads:
        t.start()
    t0 = time.monotonic()
    sys.stdin.readline()  # the benchmark says when to stop
    elapsed = time.monotonic() - t0
    stop.set()
    for t in threads:
        t.join(10)
    print(" ".join(f"{c / elapsed:.1f}" for c in counts), flush=True)
    """
)


@contextlib.contextmanager
def websocket_tabs(sim: Sim, nice: int = 0) -> Iterator[list[float]]:
    """Three pendant feeds in another process; yields a list filled with each tab's Hz."""
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


def one_run(duration: float, warmup: float, tabs: str, nice: int = 0) -> dict[str, object]:
    with running_sim() as sim:
        if tabs == "none":
            result = asyncio.run(stream_and_listen(sim, duration, warmup))
            result["tab_hz"] = []
            return result
        opener = browser_tabs(sim) if tabs == "browser" else websocket_tabs(sim, nice)
        with opener as rates:
            result = asyncio.run(stream_and_listen(sim, duration, warmup))
        result["tab_hz"] = rates
        return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=30.0, help="measured seconds per run")
    parser.add_argument("--warmup", type=float, default=3.0, help="seconds before measuring")
    parser.add_argument("--rounds", type=int, default=3, help="alternations of both runs")
    parser.add_argument("--browser", action="store_true", help="real Chromium tabs")
    parser.add_argument(
        "--tab-nice",
        type=int,
        default=0,
        help="run the WebSocket tabs under nice N: tells the simulator's own cost from "
        "the CPU the tabs' process takes from it on a 2-core machine",
    )
    args = parser.parse_args()
    kind = "browser" if args.browser else "websocket"
    rows: dict[str, list[float]] = {"none": [], kind: []}
    for r in range(args.rounds):
        for tabs in ("none", kind):
            res = one_run(args.duration, args.warmup, tabs, args.tab_nice)
            tick = res["tick"]
            assert isinstance(tick, dict)
            late = tick["lateness_ms"]
            rows[tabs].append(late["p99"])
            hz = ", ".join(f"{x:.1f}" for x in res["tab_hz"])  # type: ignore[attr-defined]
            print(
                f"round {r + 1} tabs={tabs:9s} p50 {late['p50']:.3f} p99 {late['p99']:.3f} "
                f"max {late['max']:.2f} ms, overruns {tick['overruns']} of {tick['count']} "
                f"ticks, points {res['points']}" + (f", tab Hz [{hz}]" if hz else ""),
                flush=True,
            )
    base = sorted(rows["none"])[len(rows["none"]) // 2]
    with_tabs = sorted(rows[kind])[len(rows[kind]) // 2]
    print(
        json.dumps(
            {
                "median_p99_ms_without_tabs": round(base, 3),
                f"median_p99_ms_with_{TABS}_{kind}_tabs": round(with_tabs, 3),
                "ratio": round(with_tabs / base, 2) if base else None,
            }
        )
    )


if __name__ == "__main__":
    main()
