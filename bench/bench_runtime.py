"""Benchmarks of the servers and the interpolation loop (prints numbers; not a test).

    python bench/bench_runtime.py                 # the recorded run: 60 s of streaming
    python bench/bench_runtime.py --duration 10   # a quick look while developing

What it measures, each against a ``pymotoros sim`` subprocess on 127.0.0.1 port 0:

1. start-up: seconds from spawning ``pymotoros sim`` to its ready line (median of N);
2. interpolation-loop lateness p50/p99/max and overruns over ``--duration`` seconds while
   a trajectory streams (JOINT_TRAJ_PT_FULL with BUSY retries, a back-and-forth sweep of
   joint 1) and four state clients read the stream; read from the control API after a
   ``POST /api/tick/reset`` at the end of a warm-up;
3. motion-port round trip of CHECK_QUEUE_CNT (blocking socket, one request in flight)
   next to a plain asyncio echo server answering a 68-byte message with 76 bytes;
4. resident memory of the simulator (VmRSS and peak VmHWM) after the run;
5. the machine's floor: the same ``Ticker`` and ``LoopClock`` ticking a step that does
   nothing, alone in a fresh process for ``--floor`` seconds. No loop on this machine can
   be more punctual than that; it tells the simulator's own cost from the machine's.

``--breakdown`` measures only where a CHECK_QUEUE_CNT round trip goes (issue 13): the
simulator runs with clock marks (``time.perf_counter_ns``, the system-wide monotonic
clock, so the client's and the server's marks compare) around each step of the request
path, the client marks send and receive, and the median of each step is printed next
to the asyncio echo baseline, with how often a tick ran inside a round trip and what it
cost. The marks add their own ~1 µs per step; the totals are given with and without.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import os
import re
import signal
import socket
import statistics
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from dataclasses import dataclass

import httpx

from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port, ResultCode
from pymotoros.protocol.framing import FrameDecoder, decode_reply, encode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionCtrl, MotoMotionReply

READY = re.compile(r"pymotoros sim ready motion=(\d+) state=(\d+) io=(\d+) http=(\d+)")
ORDER = ByteOrder.LITTLE

ECHO_SERVER = textwrap.dedent(
    """
    import asyncio, sys

    REPLY = bytes(76)

    async def handle(reader, writer):
        try:
            while True:
                await reader.readexactly(68)
                writer.write(REPLY)
                await writer.drain()
        except (asyncio.IncompleteReadError, ConnectionError):
            writer.close()

    async def main():
        server = await asyncio.start_server(handle, "127.0.0.1", 0)
        print(server.sockets[0].getsockname()[1], flush=True)
        async with server:
            await server.serve_forever()

    asyncio.run(main())
    """
)


FLOOR_TICKER = textwrap.dedent(
    """
    import asyncio, json, sys
    from pymotoros.runtime.clock import PRECISE_SPIN_S, LoopClock
    from pymotoros.runtime.ticker import Ticker

    async def main(seconds):
        ticker = Ticker(lambda: None, 0.004, LoopClock(spin=PRECISE_SPIN_S))
        task = asyncio.create_task(ticker.run())
        await ticker.wait_ticks(250)  # one second of warm-up
        ticker.reset_stats()
        await ticker.wait_ticks(int(seconds / 0.004))
        task.cancel()
        stats = ticker.stats()
        print(json.dumps({"overruns": stats.overruns, "p50": stats.lateness_ms.p50,
                          "p99": stats.lateness_ms.p99, "max": stats.lateness_ms.max}))

    asyncio.run(main(float(sys.argv[1])))
    """
)


BREAKDOWN_SIM = textwrap.dedent(
    """
    # pymotoros sim with clock marks around each step of a motion request (bench only).
    import asyncio, atexit, collections, json, os, sys, time
    import pymotoros.runtime.app as app
    import pymotoros.runtime.motion_server as ms
    import pymotoros.runtime.tcp as tcp

    now = time.perf_counter_ns
    MAX_RECORDS = 100_000  # bounded: one round-trip run is a few thousand
    marks = {}
    records = []
    ticks = collections.deque(maxlen=200_000)  # (start, end) of each tick

    def wrap_sync(owner, name, label, after=True):
        real = getattr(owner, name)
        def wrapper(*args, **kwargs):
            result = real(*args, **kwargs)
            marks[label] = now()
            return result
        setattr(owner, name, wrapper)

    real_feed = asyncio.StreamReader.feed_data
    def feed_data(self, data):
        marks.setdefault("feed", now())
        real_feed(self, data)
    asyncio.StreamReader.feed_data = feed_data

    real_read = asyncio.StreamReader.read
    async def read(self, n=-1):
        data = await real_read(self, n)
        marks["read"] = now()
        return data
    asyncio.StreamReader.read = read

    class Decoder(tcp.FrameDecoder):
        def next_frame(self):
            frame = super().next_frame()
            if frame is not None:
                marks["frame"] = now()
            return frame
    tcp.FrameDecoder = Decoder

    wrap_sync(ms, "check_request", "decoded")

    real_write = asyncio.StreamWriter.write
    def write(self, data):
        marks["encoded"] = now()  # the reply's bytes are ready
        real_write(self, data)
        marks["written"] = now()
    asyncio.StreamWriter.write = write

    real_process = ms.MotionServer._process
    async def process(self, *args):
        reply = await real_process(self, *args)
        marks["processed"] = now()
        return reply
    ms.MotionServer._process = process

    real_drain = asyncio.StreamWriter.drain
    async def drain(self):
        await real_drain(self)
        marks["drained"] = now()
        if len(records) < MAX_RECORDS:
            records.append(dict(marks))
        marks.clear()
    asyncio.StreamWriter.drain = drain

    class Ticker(app.Ticker):
        def __init__(self, step, *args, **kwargs):
            def timed_step():
                start = now()
                step()
                ticks.append((start, now()))
            super().__init__(timed_step, *args, **kwargs)
    app.Ticker = Ticker

    def dump():
        with open(os.environ["BREAKDOWN_OUT"], "w") as f:
            json.dump({"records": records, "ticks": list(ticks)}, f)
    atexit.register(dump)

    from pymotoros.cli.main import main
    sys.argv = ["pymotoros", "-q", "sim", "--motion-port", "0", "--state-port", "0",
                "--io-port", "0", "--http-port", "0"]
    main()
    """
)

BREAKDOWN_STEPS = (
    ("send -> data_received", "send", "feed", "client send, loopback, epoll, loop, recv"),
    ("data_received -> task", "feed", "read", "future set, task step scheduled and run"),
    ("reassembly", "read", "frame", "FrameDecoder.feed/next_frame"),
    ("decode", "frame", "decoded", "check_request: size rules and decode"),
    ("dispatch", "decoded", "processed", "_process: controller.motion_ctrl, reply object"),
    ("encode", "processed", "encoded", "reply bytes (encoded, or found already encoded)"),
    ("send -> client has it", "encoded", "recv", "send syscall, loopback, client wake-up"),
)
"""The critical path of one round trip, in order (their medians add up to about the
whole). After the reply has left, the server still returns from write() and drain()
(printed apart: it overlaps the client's next request)."""


def breakdown(n: int) -> None:
    """Where a CHECK_QUEUE_CNT round trip goes, step by step (see the module docstring)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "marks.json")
        cmd = [sys.executable, "-c", BREAKDOWN_SIM]
        env = {**os.environ, "BREAKDOWN_OUT": out}
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env)  # noqa: S603
        assert proc.stdout is not None
        match = READY.fullmatch(proc.stdout.readline().strip())
        if match is None:
            proc.kill()
            raise SystemExit("the instrumented simulator did not start")
        request = encode(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT), ORDER)
        client = marked_round_trips(int(match.group(1)), request, 76, n)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)
        with open(out, encoding="utf-8") as f:
            dumped = json.load(f)
    records = dumped["records"][-len(client) :]
    if len(records) != len(client):
        raise SystemExit(f"{len(records)} server records for {len(client)} round trips")
    ticks = dumped["ticks"]
    echo = echo_round_trips(n)
    for rec, (send, recv) in zip(records, client, strict=True):
        rec["send"], rec["recv"] = send, recv
    total = [(r["recv"] - r["send"]) / 1000 for r in records]
    print(f"CHECK_QUEUE_CNT round trip, step by step (median over {len(records)}, µs):")
    steps_sum = 0.0
    for label, start, end, what in BREAKDOWN_STEPS:
        values = [(r[end] - r[start]) / 1000 for r in records]
        median = statistics.median(values)
        steps_sum += median
        print(f"  {label:22s} {median:7.1f}  p99 {pct(values, 0.99):7.1f}   {what}")
    print(
        f"  whole round trip       {statistics.median(total):7.1f}  p99 {pct(total, 0.99):7.1f}"
        f"   (sum of the step medians {steps_sum:.1f}; the marks cost ~1 µs per step)"
    )
    after = [(r["drained"] - r["encoded"]) / 1000 for r in records]
    print(f"  after the reply left: write() and drain() return {statistics.median(after):.1f}")
    print(
        f"  asyncio echo baseline   {pct(echo, 0.5) * 1e6:7.1f}  p99 {pct(echo, 0.99) * 1e6:7.1f}"
        f"   ratio p50 {statistics.median(total) / (pct(echo, 0.5) * 1e6):.2f}x (marks included)"
    )
    hit, stolen = 0, []
    index = 0
    starts = [t[0] for t in ticks]
    import bisect

    for r in records:
        index = bisect.bisect_left(starts, r["send"] - 4_000_000)
        overlap = 0
        for start, end in ticks[index:]:
            if start > r["recv"]:
                break
            overlap += max(0, min(end, r["recv"]) - max(start, r["send"]))
        if overlap:
            hit += 1
            stolen.append(overlap / 1000)
    tick_len = [(e - s) / 1000 for s, e in ticks]
    print(
        f"  ticker interference: a tick ran inside {hit} of {len(records)} round trips "
        f"({100 * hit / len(records):.1f} %), taking a median "
        f"{statistics.median(stolen or [0]):.1f}"
        f" µs of them; a tick lasts {statistics.median(tick_len or [0]):.1f} µs (median) in "
        "this idle twin"
    )


def marked_round_trips(port: int, request: bytes, reply_size: int, n: int) -> list[tuple[int, int]]:
    """(send, receive) perf_counter_ns of ``n`` round trips after 200 of warm-up."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        marks = []
        for i in range(n + 200):
            t0 = time.perf_counter_ns()
            sock.sendall(request)
            got = 0
            while got < reply_size:
                chunk = sock.recv(4096)
                if not chunk:
                    raise ConnectionError("server closed")
                got += len(chunk)
            if i >= 200:
                marks.append((t0, time.perf_counter_ns()))
        return marks


def floor_lateness(seconds: float) -> dict[str, float]:
    """Lateness of a do-nothing tick loop on this machine (see the module docstring)."""
    out = subprocess.run(  # noqa: S603 - our own argv
        [sys.executable, "-c", FLOOR_TICKER, str(seconds)],
        capture_output=True,
        text=True,
        check=True,
        timeout=seconds + 60,
    ).stdout
    result: dict[str, float] = json.loads(out)
    return result


@dataclass
class Sim:
    proc: subprocess.Popen[str]
    motion: int
    state: int
    io: int
    http: int
    startup_s: float


def start_sim(nice: int = 0, fifo: int = 0) -> Sim:
    cmd = [sys.executable, "-m", "pymotoros", "-q", "sim"]
    if nice:
        cmd = ["nice", "-n", str(nice), *cmd]
    if fifo:
        cmd = ["chrt", "--fifo", str(fifo), *cmd]
    cmd += ["--motion-port", "0", "--state-port", "0", "--io-port", "0", "--http-port", "0"]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)  # noqa: S603 - our own argv
    assert proc.stdout is not None
    line = proc.stdout.readline()
    startup = time.perf_counter() - t0
    match = READY.fullmatch(line.strip())
    if match is None:
        proc.kill()
        raise SystemExit(f"unexpected first line from pymotoros sim: {line!r}")
    motion, state, io, http = (int(g) for g in match.groups())
    return Sim(proc, motion, state, io, http, startup)


def stop_sim(sim: Sim) -> int:
    sim.proc.send_signal(signal.SIGTERM)
    return sim.proc.wait(timeout=30)


@contextlib.contextmanager
def running_sim(nice: int = 0, fifo: int = 0) -> Iterator[Sim]:
    sim = start_sim(nice, fifo)
    try:
        yield sim
    finally:
        code = stop_sim(sim)
        if code != 0:
            print(f"warning: pymotoros sim exited with {code}")


def http(sim: Sim, method: str, path: str) -> dict[str, object]:
    resp = httpx.request(method, f"http://127.0.0.1:{sim.http}{path}", timeout=10)
    resp.raise_for_status()
    result: dict[str, object] = resp.json()
    return result


def memory_kib(pid: int) -> tuple[int, int]:
    fields = {}
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            key, _, value = line.partition(":")
            fields[key] = value.strip()
    return int(fields["VmRSS"].split()[0]), int(fields["VmHWM"].split()[0])


def pct(samples: list[float], q: float) -> float:
    ordered = sorted(samples)
    return ordered[max(0, math.ceil(q * len(ordered)) - 1)]


# --------------------------------------------------------------------------- clients


class MotionClient:
    """asyncio motion client on raw frames (the codec only)."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader, self.writer = reader, writer
        self.decoder = FrameDecoder(ORDER)

    async def request(self, message: object) -> MotoMotionReply:
        self.writer.write(encode(message, ORDER))  # type: ignore[arg-type]
        while (frame := self.decoder.next_frame()) is None:
            data = await self.reader.read(4096)
            if not data:
                raise ConnectionError("simulator closed the motion connection")
            self.decoder.feed(data)
        reply = decode_reply(frame, ORDER, Port.MOTION)
        assert isinstance(reply, MotoMotionReply)
        return reply


async def state_reader(port: int, stop: asyncio.Event, counts: list[int]) -> None:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        while not stop.is_set():
            data = await reader.read(65536)
            if not data:
                break
            counts[0] += len(data)
    finally:
        writer.close()
        with contextlib.suppress(ConnectionError):
            await writer.wait_closed()


def sweep_point(seq: int, t: float, amplitude: float, period: float) -> JointTrajPtFull:
    w = 2 * math.pi / period
    pos = amplitude * (1 - math.cos(w * t)) / 2
    vel = amplitude * w * math.sin(w * t) / 2
    return JointTrajPtFull.for_joints(0, seq, t, [pos, 0, 0, 0, 0, 0], [vel, 0, 0, 0, 0, 0])


async def stream_and_listen(sim: Sim, duration: float, warmup: float) -> dict[str, object]:
    stop = asyncio.Event()
    counts = [0]
    async with asyncio.TaskGroup() as tg:
        for _ in range(4):
            tg.create_task(state_reader(sim.state, stop, counts))
        reader, writer = await asyncio.open_connection("127.0.0.1", sim.motion)
        client = MotionClient(reader, writer)
        reply = await client.request(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
        if reply.result != ResultCode.SUCCESS:
            raise SystemExit(f"START_TRAJ_MODE failed: {reply}")
        loop = asyncio.get_running_loop()
        start = loop.time()
        reset_at = start + warmup
        end = reset_at + duration
        seq, t, busy, points = 0, 0.0, 0, 0
        stats_reset = False
        while loop.time() < end:
            if not stats_reset and loop.time() >= reset_at:
                await asyncio.to_thread(http, sim, "POST", "/api/tick/reset")
                stats_reset = True
            reply = await client.request(sweep_point(seq, t, 0.5, 4.0))
            if reply.result == ResultCode.BUSY:
                busy += 1
                await asyncio.sleep(0.005)  # as the ROS driver does
                continue
            if reply.result != ResultCode.SUCCESS:
                raise SystemExit(f"point {seq} refused: {reply}")
            seq, t, points = seq + 1, t + 0.1, points + 1
        state = await asyncio.to_thread(http, sim, "GET", "/api/state")
        await client.request(MotoMotionCtrl(0, 0, MotionCommand.STOP_MOTION))
        writer.close()
        stop.set()
    tick = state["tick"]
    assert isinstance(tick, dict)
    return {"tick": tick, "points": points, "busy": busy, "state_bytes": counts[0]}


def round_trips(port: int, request: bytes, reply_size: int, n: int) -> list[float]:
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        samples = []
        for i in range(n + 200):
            t0 = time.perf_counter()
            sock.sendall(request)
            got = 0
            while got < reply_size:
                chunk = sock.recv(4096)
                if not chunk:
                    raise ConnectionError("server closed")
                got += len(chunk)
            if i >= 200:  # warm-up
                samples.append(time.perf_counter() - t0)
        return samples


def echo_round_trips(n: int) -> list[float]:
    cmd = [sys.executable, "-c", ECHO_SERVER]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)  # noqa: S603 - our own argv
    try:
        assert proc.stdout is not None
        port = int(proc.stdout.readline())
        return round_trips(port, bytes(68), 76, n)
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0, help="streaming seconds")
    parser.add_argument("--warmup", type=float, default=3.0, help="seconds before measuring")
    parser.add_argument("--round-trips", type=int, default=5000)
    parser.add_argument("--startups", type=int, default=5)
    parser.add_argument(
        "--floor",
        type=float,
        default=20.0,
        help="seconds of the do-nothing tick loop that measures the machine's floor (0: skip)",
    )
    parser.add_argument(
        "--sim-nice",
        type=int,
        default=0,
        help="run the simulator under `nice -n N` (negative: higher priority, needs root); "
        "shows what the loop does when the OS gives it the CPU on a busy machine",
    )
    parser.add_argument(
        "--sim-fifo",
        type=int,
        default=0,
        help="run the simulator under `chrt --fifo N` (SCHED_FIFO real-time priority, needs "
        "root or CAP_SYS_NICE), as a real-time deployment would",
    )
    parser.add_argument(
        "--breakdown",
        action="store_true",
        help="only split a CHECK_QUEUE_CNT round trip into its steps (instrumented "
        "simulator, --round-trips of them) next to the echo baseline",
    )
    args = parser.parse_args()

    print(
        f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}, "
        f"load average {os.getloadavg()[0]:.2f} at start"
    )
    if args.breakdown:
        breakdown(args.round_trips)
        print(f"load average {os.getloadavg()[0]:.2f} at the end (other work on the machine)")
        return

    startups = []
    for _ in range(args.startups):
        with running_sim() as sim:
            startups.append(sim.startup_s)
    print(
        f"start-up to ready line: median {statistics.median(startups):.2f} s "
        f"(min {min(startups):.2f}, max {max(startups):.2f}, n={len(startups)})"
    )

    with running_sim(args.sim_nice, args.sim_fifo) as sim:
        result = asyncio.run(stream_and_listen(sim, args.duration, args.warmup))
        tick = result["tick"]
        assert isinstance(tick, dict)
        late = tick["lateness_ms"]
        print(
            f"interpolation loop over {args.duration:.0f} s "
            f"(nice {args.sim_nice}, fifo {args.sim_fifo or 'off'}), "
            "trajectory streaming "
            f"({result['points']} points, {result['busy']} BUSY) + 4 state clients "
            f"({result['state_bytes'] / args.duration / 4 / 1024:.1f} KiB/s each):"
        )
        print(
            f"  lateness p50 {late['p50']:.3f} ms, p99 {late['p99']:.3f} ms, "
            f"max {late['max']:.3f} ms; {tick['count']} ticks in total, "
            f"{tick['overruns']} overruns (period {tick['period_ms']} ms)"
        )
        request = encode(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT), ORDER)
        sim_rt = round_trips(sim.motion, request, 76, args.round_trips)
        rss, hwm = memory_kib(sim.proc.pid)

    echo_rt = echo_round_trips(args.round_trips)
    for name, samples in (("CHECK_QUEUE_CNT", sim_rt), ("asyncio echo baseline", echo_rt)):
        print(
            f"round trip {name}: p50 {pct(samples, 0.5) * 1e6:.0f} us, "
            f"p99 {pct(samples, 0.99) * 1e6:.0f} us (n={len(samples)})"
        )
    print(f"  ratio p50 {pct(sim_rt, 0.5) / pct(echo_rt, 0.5):.2f}x")
    print(f"resident memory of the simulator: {rss / 1024:.1f} MiB (peak {hwm / 1024:.1f} MiB)")
    if args.floor > 0:
        floor = floor_lateness(args.floor)
        print(
            f"machine floor, a do-nothing tick loop alone for {args.floor:.0f} s: "
            f"lateness p50 {floor['p50']:.3f} ms, p99 {floor['p99']:.3f} ms, "
            f"max {floor['max']:.3f} ms, {floor['overruns']:.0f} overruns"
        )
    print(f"load average {os.getloadavg()[0]:.2f} at the end (other work on the machine)")


if __name__ == "__main__":
    main()
