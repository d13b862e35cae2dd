"""Many twins on one machine: idle CPU and loop lateness per twin (issue 13; prints numbers).

    python bench/bench_clock.py                          # the recorded run
    python bench/bench_clock.py --twins 1 --duration 5   # a quick look

For each fleet size in ``--twins`` it starts that many ``pymotoros sim`` processes on
127.0.0.1 port 0 and measures, over ``--duration`` seconds after a warm-up:

1. idle: CPU per twin (utime + stime from /proc/<pid>/stat, % of one core) and every
   twin's interpolation-loop lateness p99 (from its control API after
   ``POST /api/tick/reset``);
2. streaming: the same while each twin has its own motion client streaming a
   trajectory (JOINT_TRAJ_PT_FULL every 100 ms of trajectory time, BUSY retries) and one
   state client; all the clients run in this process.

Then, side by side in the same run, the clock alone: a do-nothing Ticker on the
TimerFdClock (the simulator's clock since issue 13), on the ThreadClock (the timer
thread, the fallback off Linux) and on the LoopClock that spins the last millisecond
(the clock before), each in a fresh process: lateness and CPU.

Contention between the clock and the servers: ``--contention`` seconds of CHECK_QUEUE_CNT
round trips back to back against one twin on its default clock (its loop as busy as a
client can make it), lateness next to idle. The timer thread's own cost (the GIL
hand-off) shows in the clock-alone comparison, thread against timerfd.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import (
    ORDER,
    MotionClient,
    Sim,
    http,
    round_trips,
    start_sim,
    state_reader,
    stop_sim,
    sweep_point,
)

from pymotoros.protocol.constants import MotionCommand, ResultCode
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import MotoMotionCtrl

CLK_TCK = os.sysconf("SC_CLK_TCK")

CLOCK_ALONE = textwrap.dedent(
    """
    import asyncio, json, os, sys
    from pymotoros.runtime.clock import PRECISE_SPIN_S, LoopClock, ThreadClock, TimerFdClock
    from pymotoros.runtime.ticker import Ticker

    async def main(kind, seconds):
        kinds = {"timerfd": TimerFdClock, "thread": ThreadClock}
        clock = kinds[kind]() if kind in kinds else LoopClock(spin=PRECISE_SPIN_S)
        ticker = Ticker(lambda: None, 0.004, clock)
        task = asyncio.create_task(ticker.run())
        await ticker.wait_ticks(250)
        ticker.reset_stats()
        t0 = os.times()
        await ticker.wait_ticks(int(seconds / 0.004))
        t1 = os.times()
        task.cancel()
        s = ticker.stats()
        cpu = (t1.user + t1.system - t0.user - t0.system) / (t1.elapsed - t0.elapsed)
        print(json.dumps({"p50": s.lateness_ms.p50, "p99": s.lateness_ms.p99,
                          "max": s.lateness_ms.max, "overruns": s.overruns, "cpu": cpu}))

    asyncio.run(main(sys.argv[1], float(sys.argv[2])))
    """
)


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime


async def stream(sim: Sim, stop: asyncio.Event) -> int:
    """Stream a back-and-forth sweep of joint 1 until ``stop``; returns points sent."""
    reader, writer = await asyncio.open_connection("127.0.0.1", sim.motion)
    client = MotionClient(reader, writer)
    reply = await client.request(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
    if reply.result != ResultCode.SUCCESS:
        raise SystemExit(f"START_TRAJ_MODE failed: {reply}")
    seq, t = 0, 0.0
    while not stop.is_set():
        reply = await client.request(sweep_point(seq, t, 0.5, 4.0))
        if reply.result == ResultCode.BUSY:
            await asyncio.sleep(0.005)  # as the ROS driver does
            continue
        if reply.result != ResultCode.SUCCESS:
            raise SystemExit(f"point {seq} refused: {reply}")
        seq, t = seq + 1, t + 0.1
    await client.request(MotoMotionCtrl(0, 0, MotionCommand.STOP_MOTION))
    writer.close()
    return seq


async def measure(sims: list[Sim], duration: float, warmup: float, streaming: bool) -> None:
    stop = asyncio.Event()
    counts = [0]
    async with asyncio.TaskGroup() as tg:
        if streaming:
            for sim in sims:
                tg.create_task(stream(sim, stop))
                tg.create_task(state_reader(sim.state, stop, counts))
        await asyncio.sleep(warmup)
        for sim in sims:
            await asyncio.to_thread(http, sim, "POST", "/api/tick/reset")
        cpu0 = [cpu_seconds(s.proc.pid) for s in sims]
        t0 = time.monotonic()
        await asyncio.sleep(duration)
        cpu1 = [cpu_seconds(s.proc.pid) for s in sims]
        elapsed = time.monotonic() - t0
        states = [await asyncio.to_thread(http, s, "GET", "/api/state") for s in sims]
        stop.set()
    cpus = [100 * (b - a) / elapsed for a, b in zip(cpu0, cpu1, strict=True)]
    p99s, maxes, overruns = [], [], 0
    for state in states:
        tick = state["tick"]
        assert isinstance(tick, dict)
        p99s.append(tick["lateness_ms"]["p99"])
        maxes.append(tick["lateness_ms"]["max"])
        overruns += tick["overruns"]
    what = "streaming" if streaming else "idle"
    print(
        f"  {len(sims):2d} twins {what:9s}: CPU per twin mean {sum(cpus) / len(cpus):.1f} % "
        f"(max {max(cpus):.1f} %, total {sum(cpus):.0f} %); lateness p99 worst twin "
        f"{max(p99s):.3f} ms, median twin {sorted(p99s)[len(p99s) // 2]:.3f} ms; "
        f"max {max(maxes):.1f} ms; {overruns} overruns"
    )


def clock_alone(kind: str, seconds: float) -> dict[str, float]:
    out = subprocess.run(  # noqa: S603 - our own argv
        [sys.executable, "-c", CLOCK_ALONE, kind, str(seconds)],
        capture_output=True,
        text=True,
        check=True,
        timeout=seconds + 60,
    ).stdout
    result: dict[str, float] = json.loads(out)
    return result


def contention(seconds: float, warmup: float) -> None:
    sim = start_sim()
    try:
        time.sleep(warmup)
        http(sim, "POST", "/api/tick/reset")
        time.sleep(seconds)
        idle = http(sim, "GET", "/api/state")["tick"]
        http(sim, "POST", "/api/tick/reset")
        request = encode(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT), ORDER)
        t0 = time.monotonic()
        n = 0
        while time.monotonic() - t0 < seconds:
            n += len(round_trips(sim.motion, request, 76, 1000))
        busy = http(sim, "GET", "/api/state")["tick"]
    finally:
        stop_sim(sim)
    assert isinstance(idle, dict)
    assert isinstance(busy, dict)
    for name, tick in (("idle", idle), ("round trips back to back", busy)):
        late = tick["lateness_ms"]
        print(
            f"  {name:24s}: lateness p50 {late['p50']:.3f} ms, p99 {late['p99']:.3f} ms, "
            f"max {late['max']:.1f} ms, {tick['overruns']} overruns"
        )
    print(f"  ({n} round trips in {seconds:.0f} s)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--twins", type=int, nargs="+", default=[1, 8, 16])
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--warmup", type=float, default=3.0)
    parser.add_argument("--alone", type=float, default=20.0, help="seconds per clock alone")
    parser.add_argument("--contention", type=float, default=10.0)
    parser.add_argument("--no-stream", action="store_true", help="idle fleets only")
    args = parser.parse_args()
    print(
        f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}, "
        f"load average {os.getloadavg()[0]:.2f} at start"
    )
    for n in args.twins:
        sims = [start_sim() for _ in range(n)]
        try:
            asyncio.run(measure(sims, args.duration, args.warmup, streaming=False))
            if not args.no_stream:
                asyncio.run(measure(sims, args.duration, args.warmup, streaming=True))
        finally:
            for sim in sims:
                with contextlib.suppress(Exception):
                    stop_sim(sim)
    if args.alone > 0:
        print(f"the clock alone, a do-nothing 4 ms ticker, {args.alone:.0f} s each:")
        for kind in ("timerfd", "thread", "loop-spin"):
            r = clock_alone(kind, args.alone)
            print(
                f"  {kind:9s}: CPU {100 * r['cpu']:.1f} %, lateness p50 {r['p50']:.3f} ms, "
                f"p99 {r['p99']:.3f} ms, max {r['max']:.1f} ms, {r['overruns']:.0f} overruns"
            )
    if args.contention > 0:
        print("the default (timerfd) clock vs a busy motion server on the same loop (one twin):")
        contention(args.contention, args.warmup)
    print(f"load average {os.getloadavg()[0]:.2f} at the end (other work on the machine)")


if __name__ == "__main__":
    main()
