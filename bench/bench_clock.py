"""Many twins on one machine: idle CPU and loop lateness per twin (issue 13; prints numbers).

    python bench/bench_clock.py                          # the recorded run
    python bench/bench_clock.py --twins 1 --duration 5   # a quick look
    python bench/bench_clock.py --alone 0 --contention 0 --realtime both \
        --client-procs 2 --client-nice 19 --idle-duration 10   # --realtime side by side

For each fleet size in ``--twins`` it starts that many ``pymotoros sim`` processes on
127.0.0.1 port 0 and measures, over ``--duration`` seconds after a warm-up:

1. idle: CPU per twin (utime + stime from /proc/<pid>/stat, % of one core) and every
   twin's interpolation-loop lateness p99 (from its control API after
   ``POST /api/tick/reset``); then the memory per twin (RSS, PSS and private pages
   from /proc/<pid>/smaps_rollup: PSS is what each twin costs the machine);
2. streaming: the same while each twin has its own motion client streaming a
   trajectory (JOINT_TRAJ_PT_FULL every 100 ms of trajectory time, BUSY retries) and one
   state client; the clients run in this process, or with ``--client-procs K`` in K
   processes of their own (at ``--client-nice``, e.g. 19, so that they load the
   machine without competing with the twins at the same priority).

``--slice-us 0 100`` runs each fleet once per EEVDF time slice asked for the twins'
threads with ``sched_setattr`` (0: the kernel's default; unprivileged, Linux >= 6.12).

``--realtime on|off|both`` starts the twins with ``pymotoros sim --realtime``
(SCHED_FIFO, low priority), without, or each fleet once each way, one after the other
in the same run; ``--batching off`` starts them with ``--no-idle-batching`` (idle
batching is on by default since issue 13: an unconnected twin ticks in batches of
100 ms; the idle figures then measure the batch wake-ups, see docs/sim.md).

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
import ctypes
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import (
    ORDER,
    READY,
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


class _SchedAttr(ctypes.Structure):
    """struct sched_attr (linux/sched/types.h, SCHED_ATTR_SIZE_VER1: 56 bytes)."""

    _fields_ = [
        ("size", ctypes.c_uint32),
        ("sched_policy", ctypes.c_uint32),
        ("sched_flags", ctypes.c_uint64),
        ("sched_nice", ctypes.c_int32),
        ("sched_priority", ctypes.c_uint32),
        ("sched_runtime", ctypes.c_uint64),
        ("sched_deadline", ctypes.c_uint64),
        ("sched_period", ctypes.c_uint64),
        ("sched_util_min", ctypes.c_uint32),
        ("sched_util_max", ctypes.c_uint32),
    ]


SYS_SCHED_SETATTR = 314  # x86-64 syscall numbers
SYS_SCHED_GETATTR = 315


def set_fair_slice(pid: int, slice_ns: int) -> None:
    """Ask EEVDF (Linux >= 6.12) for a ``slice_ns`` time slice for every thread of
    ``pid``, keeping its policy (SCHED_OTHER) and niceness: no privilege needed. A
    shorter slice gives a waking task an earlier virtual deadline, so it should preempt
    sooner (the kernel's default here is 1.4 ms on 2 CPUs)."""
    libc = ctypes.CDLL(None, use_errno=True)
    for tid in os.listdir(f"/proc/{pid}/task"):
        attr = _SchedAttr()
        size = ctypes.sizeof(attr)
        if libc.syscall(SYS_SCHED_GETATTR, int(tid), ctypes.byref(attr), size, 0) != 0:
            raise OSError(ctypes.get_errno(), "sched_getattr")
        attr.size = size
        attr.sched_flags = 0
        attr.sched_runtime = slice_ns
        if libc.syscall(SYS_SCHED_SETATTR, int(tid), ctypes.byref(attr), 0) != 0:
            raise OSError(ctypes.get_errno(), "sched_setattr (needs Linux >= 6.12 for a slice)")


def memory_kib(pid: int) -> dict[str, int]:
    """Rss, Pss and Private_Dirty of a process (kB, /proc/<pid>/smaps_rollup).

    Pss shares each page among the processes mapping it, so a fleet's memory is the sum
    of its twins' Pss; Rss counts the shared libraries (numpy, Pinocchio, ...) in full
    in every twin. Private_Dirty is what one more twin adds at least.
    """
    out: dict[str, int] = {}
    with open(f"/proc/{pid}/smaps_rollup", encoding="ascii") as f:
        for line in f:
            key, _, rest = line.partition(":")
            if key in ("Rss", "Pss", "Private_Dirty"):
                out[key] = int(rest.split()[0])
    return out


def print_memory(sims: list[Sim]) -> None:
    rows = [memory_kib(s.proc.pid) for s in sims]

    def mean_mib(key: str) -> float:
        return sum(r[key] for r in rows) / len(rows) / 1024

    print(
        f"  {len(sims):2d} twins memory: per twin RSS {mean_mib('Rss'):.1f} MiB, "
        f"PSS {mean_mib('Pss'):.1f} MiB, private {mean_mib('Private_Dirty'):.1f} MiB; "
        f"the fleet's PSS {sum(r['Pss'] for r in rows) / 1024:.0f} MiB"
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


def start_twins(n: int, extra: list[str]) -> list[Sim]:
    """Start ``n`` twins at once (their start-ups overlap), each on OS-chosen ports."""
    cmd = [sys.executable, "-m", "pymotoros", "-q", "sim", *extra]
    cmd += ["--motion-port", "0", "--state-port", "0", "--io-port", "0", "--http-port", "0"]
    t0 = time.perf_counter()
    procs = [
        subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)  # noqa: S603 - our own argv
        for _ in range(n)
    ]
    sims = []
    for proc in procs:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        match = READY.fullmatch(line.strip())
        if match is None:
            for p in procs:
                p.kill()
            raise SystemExit(f"unexpected first line from pymotoros sim: {line!r}")
        motion, state, io, port = (int(g) for g in match.groups())
        sims.append(Sim(proc, motion, state, io, port, time.perf_counter() - t0))
    return sims


def stop_twins(sims: list[Sim]) -> None:
    """SIGTERM every twin at once, then wait for each (stopping one by one takes long)."""
    for sim in sims:
        with contextlib.suppress(ProcessLookupError):
            sim.proc.send_signal(signal.SIGTERM)
    for sim in sims:
        try:
            sim.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            sim.proc.kill()
            sim.proc.wait()


async def clients_for(ports: list[tuple[int, int]], seconds: float) -> None:
    """One streaming motion client and one state reader per twin, for ``seconds``."""
    stop = asyncio.Event()
    counts = [0]
    async with asyncio.TaskGroup() as tg:
        for motion, state in ports:
            sim = Sim(None, motion, state, 0, 0, 0.0)  # type: ignore[arg-type]
            tg.create_task(stream(sim, stop))
            tg.create_task(state_reader(state, stop, counts))
        await asyncio.sleep(seconds)
        stop.set()


def client_worker(argv: list[str]) -> None:
    """``bench_clock.py --client-worker NICE SECONDS MOTION:STATE ...`` (a child process)."""
    nice, seconds = int(argv[0]), float(argv[1])
    if nice:
        os.nice(nice)
    ports = [(int(m), int(s)) for m, s in (a.split(":") for a in argv[2:])]
    asyncio.run(clients_for(ports, seconds))


def spawn_clients(
    sims: list[Sim], procs: int, nice: int, seconds: float
) -> list[subprocess.Popen[bytes]]:
    """The load-generating clients in ``procs`` processes of their own, at ``nice``."""
    groups = [sims[i::procs] for i in range(min(procs, len(sims)))]
    return [
        subprocess.Popen(  # noqa: S603 - our own argv
            [
                sys.executable,
                __file__,
                "--client-worker",
                str(nice),
                str(seconds),
                *(f"{s.motion}:{s.state}" for s in group),
            ]
        )
        for group in groups
    ]


async def measure(
    sims: list[Sim],
    duration: float,
    warmup: float,
    streaming: bool,
    label: str = "",
    client_procs: int = 0,
    client_nice: int = 0,
) -> dict[str, float]:
    stop = asyncio.Event()
    counts = [0]
    children: list[subprocess.Popen[bytes]] = []
    if streaming and client_procs > 0:
        children = spawn_clients(sims, client_procs, client_nice, warmup + duration + 2.0)
    async with asyncio.TaskGroup() as tg:
        if streaming and not children:
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
    for child in children:
        try:
            child.wait(timeout=30)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
        if child.returncode != 0:
            raise SystemExit(f"a client process failed (exit {child.returncode})")
    cpus = [100 * (b - a) / elapsed for a, b in zip(cpu0, cpu1, strict=True)]
    p99s, maxes, overruns = [], [], 0
    for state in states:
        tick = state["tick"]
        assert isinstance(tick, dict)
        p99s.append(tick["lateness_ms"]["p99"])
        maxes.append(tick["lateness_ms"]["max"])
        overruns += tick["overruns"]
    what = "streaming" if streaming else "idle"
    result = {
        "cpu": sum(cpus) / len(cpus),
        "cpu_total": sum(cpus),
        "p99_worst": max(p99s),
        "p99_median": sorted(p99s)[len(p99s) // 2],
        "max": max(maxes),
        "overruns": overruns,
    }
    print(
        f"  {len(sims):2d} twins {what:9s}{label}: CPU per twin mean {result['cpu']:.1f} % "
        f"(max {max(cpus):.1f} %, total {sum(cpus):.0f} %); lateness p99 worst twin "
        f"{max(p99s):.3f} ms, median twin {result['p99_median']:.3f} ms; "
        f"max {max(maxes):.1f} ms; {overruns} overruns; load {os.getloadavg()[0]:.2f}",
        flush=True,
    )
    return result


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
    if sys.argv[1:2] == ["--client-worker"]:
        client_worker(sys.argv[2:])
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--twins", type=int, nargs="+", default=[1, 8, 16])
    parser.add_argument("--duration", type=float, default=30.0, help="seconds streaming")
    parser.add_argument(
        "--idle-duration", type=float, default=None, help="seconds idle (default --duration)"
    )
    parser.add_argument("--warmup", type=float, default=3.0)
    parser.add_argument("--alone", type=float, default=20.0, help="seconds per clock alone")
    parser.add_argument("--contention", type=float, default=10.0)
    parser.add_argument("--no-stream", action="store_true", help="idle fleets only")
    parser.add_argument(
        "--realtime",
        choices=("off", "on", "both"),
        default="off",
        help="start the twins with `pymotoros sim --realtime` (both: each fleet each way)",
    )
    parser.add_argument(
        "--batching",
        choices=("on", "off", "both"),
        default="on",
        help="idle batching (off: --no-idle-batching)",
    )
    parser.add_argument(
        "--client-procs",
        type=int,
        default=0,
        help="run the streaming clients in this many processes of their own (0: here)",
    )
    parser.add_argument("--client-nice", type=int, default=0, help="niceness of those processes")
    parser.add_argument(
        "--slice-us",
        type=int,
        nargs="+",
        default=[0],
        help="EEVDF time slice asked for the twins' threads, µs, one fleet each (0: the "
        "kernel's default); e.g. --slice-us 0 100 compares them in one run",
    )
    args = parser.parse_args()
    idle_duration = args.duration if args.idle_duration is None else args.idle_duration
    print(
        f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}, "
        f"load average {os.getloadavg()[0]:.2f} at start"
    )
    variants: list[tuple[str, list[str], int]] = []
    for rt in ("off", "on") if args.realtime == "both" else (args.realtime,):
        for batch in ("on", "off") if args.batching == "both" else (args.batching,):
            for slice_us in args.slice_us:
                extra = (["--realtime"] if rt == "on" else []) + (
                    ["--no-idle-batching"] if batch == "off" else []
                )
                label = (
                    (" realtime" if rt == "on" else "")
                    + (" unbatched" if batch == "off" else "")
                    + (f" slice {slice_us} us" if slice_us else "")
                )
                variants.append((label, extra, slice_us))
    table: list[tuple[int, str, str, dict[str, float]]] = []
    for n in args.twins:
        for label, extra, slice_us in variants:
            t0 = time.monotonic()
            sims = start_twins(n, extra)
            for sim in sims if slice_us else ():
                set_fair_slice(sim.proc.pid, slice_us * 1000)
            print(f"  ({n} twins{label} started in {time.monotonic() - t0:.1f} s)", flush=True)
            try:
                r = asyncio.run(measure(sims, idle_duration, args.warmup, False, label))
                table.append((n, "idle", label, r))
                print_memory(sims)
                if not args.no_stream:
                    r = asyncio.run(
                        measure(
                            sims,
                            args.duration,
                            args.warmup,
                            True,
                            label,
                            args.client_procs,
                            args.client_nice,
                        )
                    )
                    table.append((n, "streaming", label, r))
            finally:
                stop_twins(sims)
    if len(variants) > 1:
        print("side by side (p99 worst twin / median twin, ms; CPU per twin %):")
        for n, what, label, r in table:
            print(
                f"  {n:2d} twins {what:9s} {label.strip() or 'default':20s} "
                f"p99 {r['p99_worst']:7.3f} / {r['p99_median']:7.3f}  "
                f"CPU {r['cpu']:4.1f} %  overruns {r['overruns']:.0f}"
            )
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
