"""Streaming fleets on a 2-core machine: 16 cells arranged several ways, side by side, and
the floor under the same load (issue 22, item 4; prints numbers, not a test).

    python bench/bench_fleet.py                         # the recorded run (~3 minutes)
    python bench/bench_fleet.py --duration 5 --warmup 2 # a quick look (the check run)
    python bench/bench_fleet.py --arrangements 16x1 floor16x1 --duration 60
    python bench/bench_fleet.py --realtime              # the same with `sim --realtime`
    python bench/bench_fleet.py --client-nice 0         # clients at the cells' priority
    python bench/bench_fleet.py --rounds 3              # alternating, then the best of each

Every default arrangement holds 16 cells, and every arrangement carries the same load
per cell: each cell has one motion client streaming a trajectory (JOINT_TRAJ_PT_FULL every
100 ms of trajectory time, BUSY retries every 5 ms as the ROS driver does) and one state
client, run by the same ``--client-procs`` client processes (default 2, at
``--client-nice``, default 19 as in the recorded fleet figures of issue 13 and as
docs/fleet.md advises for the load you control; 0 for clients that compete at the
cells' priority), started spread over 0.8 s as independent users would. The cells run
with default scheduling (``--realtime``: each served process asks for SCHED_FIFO as
``pymotoros sim --realtime`` does). Arrangements (``--arrangements``):

* ``PxC`` (e.g. ``16x1``, ``4x4``, ``2x8``): P processes of C HC10/YRC1000 cells each,
  served as ``pymotoros sim`` serves them (one cell: a :class:`SimulatorApp`, the command
  with one cell; several: a :class:`Fleet`, ``pymotoros sim --config ... --config ...``:
  one ticker ticks every cell of the process in turn). ``16x1`` is today's one process
  per twin;
* ``floorPxC`` (e.g. ``floor16x1``): the floor. P processes each waking every 4 ms on the
  same clock (a :class:`Ticker` on the timerfd clock, ``precise_clock()``, as a twin's)
  and doing nothing in its tick, behind C stand-ins of a cell's MotoROS ports for the same
  clients: the motion stand-in answers every request at once (SUCCESS, or BUSY while
  more than :data:`QUEUE_AHEAD_S` of trajectory is queued, which is when the twin says
  BUSY), the state stand-in sends each client a JOINT_FEEDBACK and a ROBOT_STATUS
  1 ms apart every 25 ms (the twin's cycle). So the floor has the twin's wake-ups (the
  tick, every request, every state message) and the same client processes doing the
  same work, but none of the controller's work: what the machine's scheduler alone
  costs a 4 ms loop under that load. The traffic columns show that the load matched.

Lateness is measured in the same way in every arrangement: before each cell's tick, how
long after the tick's deadline it starts (``time.monotonic()`` minus the ticker's
``next_deadline``), every tick of the ``--duration`` window after ``--warmup``, every
cell. In a process of several cells a cell ticks after the cells before it, so its
lateness adds their ticks' time: "first/last" shows the first cell's (the loop's own
lateness, what ``GET /api/state`` reports) and the last cell's p99.

"probe p99": beside every twin arrangement (unless ``--no-probe``) one more process
runs a do-nothing 4 ms ticker that no client talks to (a floor process of one cell,
left unconnected): the floor under exactly that arrangement's load, twins' work
included, at the cost of one more waker (~1.5 % of a core) among the 16 cells. The
``floor`` arrangement is the floor with the twins' wake-ups and client load but none of
their work; the probe is the floor with all of it.

Per arrangement: lateness p50/p99/max over all cells' ticks pooled; p99 of the worst
cell and of the median cell; the first and last cell's p99 (mean over processes); the
tickers' overruns; CPU per cell (the cells' processes' utime + stime from /proc, % of one
core, divided by the cells) and of the client processes in all; the machine's busy and
steal share from /proc/stat over the window (steal: time a hypervisor gave to other
guests while this VM wanted the CPU); the 1-minute load average at the end; the traffic
per cell (points accepted, requests and state bytes per second: a twin that falls behind
accepts fewer points and answers fewer BUSY retries); and how long the processes took to
print their ready lines.

Bounded: every server listens on 127.0.0.1 port 0; each arrangement's processes are
started, measured for ``--warmup + --duration`` s and stopped (SIGTERM, then SIGKILL after
:data:`STOP_TIMEOUT_S`); every wait on a child has a timeout. With the defaults (5
arrangements, 3 + 20 s each) the run takes about 3 minutes on a quiet machine.

Checked once, not recorded (2026-11-26 21:35 UTC, the 2-core machine shared with other
engineers' test runs, load average 7.3 at the start and 19.6 at the end, so every figure
of that run is the other work's, not the fleet's: 16 twins took 2 minutes to start)::

    python bench/bench_fleet.py --duration 5 --warmup 2

The recorded figures go to docs/benchmarks.md, measured on a quiet machine with the
defaults.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import os
import re
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import ORDER, MotionClient, sweep_point

from pymotoros.protocol.constants import MotionCommand, Port, ResultCode
from pymotoros.protocol.framing import FrameDecoder, decode_request, encode
from pymotoros.protocol.messages import (
    JointFeedback,
    JointTrajPtFull,
    MotoMotionCtrl,
    MotoMotionReply,
    RobotStatus,
)

CLK_TCK: Final = os.sysconf("SC_CLK_TCK")
PERIOD_S: Final = 0.004
"""The HC10/YRC1000's interpolation period (the floor's tickers use the same)."""
BUDGET_MS: Final = 1.0
"""Issue 22 item 4: loop lateness p99 <= 1 ms."""
QUEUE_AHEAD_S: Final = 0.9
"""The motion stand-in says BUSY to a point more than this far (trajectory time) ahead of
the time since the trajectory started: measured on the twin with the same client, it
takes the first 10 points (0.0 to 0.9 s) at once, then one per 100 ms."""
BUSY_RETRY_S: Final = 0.005
"""The ROS driver's retry interval after a BUSY reply (as bench_clock.py)."""
STATE_PERIOD_S: Final = 0.025
STATE_MESSAGE_GAP_S: Final = 0.001
"""The twin's state cycle and the spacing of its messages (runtime/state_server.py)."""
STAGGER_S: Final = 0.8
"""The clients' starts are spread over this, as independent users would (bench_cells.py)."""
READY_TIMEOUT_S: Final = 300.0
"""How long an arrangement's processes may take, all together, to print their ready lines
(16 twins start in ~10 s on a quiet 2-core machine; on a loaded one it took 2 minutes)."""
STATS_TIMEOUT_S: Final = 30.0
STOP_TIMEOUT_S: Final = 30.0
CELL: Final = Path(__file__).resolve().parents[1] / "examples" / "cells" / "hc10_yrc1000.toml"
READY = re.compile(r"pymotoros sim ready motion=(\d+) state=(\d+) io=(\d+) http=(\d+)( cell=\S+)?")
ARRANGEMENT = re.compile(r"(floor)?(\d+)x(\d+)")


# --------------------------------------------------------------------------- in the served process


class Probes:
    """Each cell's tick-start lateness (s), a ring per cell of ``capacity`` samples."""

    def __init__(self, cells: int, capacity: int) -> None:
        self.samples = np.zeros((cells, capacity), dtype=np.float64)
        self.counts = [0] * cells

    def sample(self, row: int, late: float) -> None:
        n = self.counts[row]
        self.samples[row, n % self.samples.shape[1]] = late
        self.counts[row] = n + 1

    def reset(self) -> None:
        self.counts = [0] * len(self.counts)

    def save(self, path: Path) -> None:
        """The samples of the window, one row per cell (a row cut to the shortest)."""
        n = min(min(self.counts), self.samples.shape[1])
        np.save(path, self.samples[:, :n])


def probed(tick: Callable[[], None], probes: Probes, row: int, ticker: Callable[[], Any]) -> Any:
    """``tick`` preceded by a lateness sample of cell ``row`` (not while batching: deferred
    ticks are late on purpose)."""
    monotonic = time.monotonic

    def run() -> None:
        t = ticker()
        deadline = t.next_deadline
        if deadline is not None and not t.batching:
            probes.sample(row, monotonic() - deadline)
        tick()

    return run


def serve(kind: str, cells: int, capacity: int, samples: Path, realtime: bool) -> None:
    """``bench_fleet.py --serve KIND CELLS CAPACITY SAMPLES [--rt]``: the measured process.

    Prints one ready line per cell; SIGUSR1 forgets the samples (end of the warm-up);
    SIGUSR2 saves them to ``samples`` and prints ``stats {json}``; SIGTERM stops."""
    if realtime:
        from pymotoros.runtime.realtime import request_realtime

        request_realtime()
    probes = Probes(cells, capacity)
    holder: list[Any] = []  # the ticker, once built

    def reset() -> None:
        probes.reset()
        holder[0].reset_stats()

    def report() -> None:
        probes.save(samples)
        stats = holder[0].stats()
        print("stats " + json.dumps({"overruns": stats.overruns}), flush=True)

    async def main(run: Callable[[], Any]) -> None:
        loop = asyncio.get_running_loop()
        loop.add_signal_handler(signal.SIGUSR1, reset)
        loop.add_signal_handler(signal.SIGUSR2, report)
        await run()

    if kind == "floor":
        asyncio.run(main(lambda: serve_floor(cells, probes, holder)))
    else:
        asyncio.run(main(twin_server(cells, probes, holder)))


def twin_server(cells: int, probes: Probes, holder: list[Any]) -> Callable[[], Any]:
    """``cells`` HC10/YRC1000 cells served as ``pymotoros sim`` serves them."""
    from pymotoros.cli.ports_file import CellLabel
    from pymotoros.cli.sim import run_simulator
    from pymotoros.cli.sim_cells import run_fleet
    from pymotoros.cli.sim_serving import simulator_config
    from pymotoros.controller import VirtualController
    from pymotoros.controller.cell import load_cell
    from pymotoros.runtime.app import SimulatorApp
    from pymotoros.runtime.fleet import Fleet, FleetCell

    cell = load_cell(CELL)
    controllers = []
    for row in range(cells):
        controller = VirtualController(cell)
        # the ticker takes the bound tick when built: probe it first
        controller.tick = probed(controller.tick, probes, row, lambda: holder[0])  # type: ignore[method-assign]
        controllers.append(controller)
    config = simulator_config("127.0.0.1", (0, 0, 0, 0), cell)  # as `pymotoros sim` builds it
    if cells == 1:
        app = SimulatorApp(controllers[0], config)
        holder.append(app.ticker)
        return lambda: run_simulator(app, None, CellLabel.of("cell", cell, CELL))
    names = [f"cell{i:02d}" for i in range(cells)]
    fleet = Fleet([FleetCell(n, c, config) for n, c in zip(names, controllers, strict=True)])
    holder.append(fleet.ticker)
    labels = [CellLabel.of(n, cell, CELL) for n in names]
    return lambda: run_fleet(fleet, labels, None)


async def serve_floor(cells: int, probes: Probes, holder: list[Any]) -> None:
    """A do-nothing 4 ms ticker behind ``cells`` stand-ins of a cell's MotoROS ports."""
    from pymotoros.runtime.clock import precise_clock
    from pymotoros.runtime.ticker import Ticker

    rows = range(cells)
    monotonic = time.monotonic

    def step() -> None:
        deadline = ticker.next_deadline
        if deadline is not None:
            now = monotonic()
            for row in rows:
                probes.sample(row, now - deadline)

    ticker = Ticker(step, PERIOD_S, precise_clock())
    holder.append(ticker)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    loop.add_signal_handler(signal.SIGTERM, stop.set)
    servers = []
    lines = []
    for _ in rows:
        motion = await asyncio.start_server(motion_stand_in, "127.0.0.1", 0)
        state = await asyncio.start_server(state_stand_in, "127.0.0.1", 0)
        servers += [motion, state]
        m, s = (srv.sockets[0].getsockname()[1] for srv in (motion, state))
        lines.append(f"pymotoros sim ready motion={m} state={s} io=0 http=0")
    print("\n".join(lines), flush=True)
    ticking = asyncio.create_task(ticker.run())
    try:
        await stop.wait()
    finally:
        ticking.cancel()
        for srv in servers:
            srv.close()
        for writer in list(OPEN):  # a handler then reads EOF and returns
            writer.close()
        if HANDLERS:
            await asyncio.wait(HANDLERS, timeout=STOP_TIMEOUT_S)


OPEN: set[asyncio.StreamWriter] = set()
HANDLERS: set[asyncio.Task[Any]] = set()
"""The stand-ins' connections and handler tasks, closed and awaited at the end (so that no
handler is cancelled under asyncio's stream callback, which would log it)."""


def tracked(writer: asyncio.StreamWriter) -> None:
    OPEN.add(writer)
    task = asyncio.current_task()
    assert task is not None
    HANDLERS.add(task)
    task.add_done_callback(HANDLERS.discard)


async def motion_stand_in(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    """Answer every request at once: SUCCESS, or BUSY for a point too far ahead."""
    tracked(writer)
    decoder = FrameDecoder(ORDER)
    start: float | None = None
    zeros = (0.0,) * 10
    try:
        while data := await reader.read(4096):
            decoder.feed(data)
            while (frame := decoder.next_frame()) is not None:
                message = decode_request(frame, ORDER, Port.MOTION)
                result = ResultCode.SUCCESS
                if isinstance(message, JointTrajPtFull):
                    now = time.monotonic()
                    if start is None:
                        start = now - message.time
                    if message.time - (now - start) > QUEUE_AHEAD_S:
                        result = ResultCode.BUSY
                    reply = MotoMotionReply(0, message.sequence, frame.msg_type, result, 0, zeros)
                elif isinstance(message, MotoMotionCtrl):
                    start = None
                    reply = MotoMotionReply(0, message.sequence, message.command, result, 0, zeros)
                else:
                    raise SystemExit(f"the motion stand-in got an unexpected {message!r}")
                writer.write(encode(reply, ORDER))
    except ConnectionError:
        pass
    finally:
        OPEN.discard(writer)
        writer.close()


async def state_stand_in(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    """A JOINT_FEEDBACK and a ROBOT_STATUS, 1 ms apart, every 25 ms until the client goes."""
    tracked(writer)
    feedback = encode(JointFeedback.for_joints(0, [0.0] * 6, [0.0] * 6), ORDER)
    status = encode(RobotStatus(1, 0, 0, 0, 1, 2, 1), ORDER)
    loop = asyncio.get_running_loop()

    async def send() -> None:
        deadline = loop.time()
        while True:
            writer.write(feedback)
            await asyncio.sleep(deadline + STATE_MESSAGE_GAP_S - loop.time())
            writer.write(status)
            await writer.drain()
            deadline += STATE_PERIOD_S
            if loop.time() - deadline > STATE_PERIOD_S:
                deadline = loop.time()  # stalled: restart the rhythm, as the twin does
            await asyncio.sleep(deadline - loop.time())

    sender = asyncio.create_task(send())
    try:
        while await reader.read(4096):
            pass
    except ConnectionError:
        pass
    finally:
        sender.cancel()
        with contextlib.suppress(asyncio.CancelledError, ConnectionError):
            await sender
        OPEN.discard(writer)
        writer.close()


# --------------------------------------------------------------------------- the clients


@dataclass
class Traffic:
    points: int = 0
    requests: int = 0
    state_bytes: int = 0


async def stream(port: int, delay: float, stop: asyncio.Event, traffic: Traffic) -> None:
    """After ``delay``, stream a back-and-forth sweep of joint 1 until ``stop``."""
    await asyncio.sleep(delay)
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    client = MotionClient(reader, writer)
    reply = await client.request(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
    if reply.result != ResultCode.SUCCESS:
        raise SystemExit(f"START_TRAJ_MODE failed: {reply}")
    seq, t = 0, 0.0
    while not stop.is_set():
        reply = await client.request(sweep_point(seq, t, 0.5, 4.0))
        traffic.requests += 1
        if reply.result == ResultCode.BUSY:
            await asyncio.sleep(BUSY_RETRY_S)
            continue
        if reply.result != ResultCode.SUCCESS:
            raise SystemExit(f"point {seq} refused: {reply}")
        traffic.points += 1
        seq, t = seq + 1, t + 0.1
    writer.close()


async def read_state(port: int, delay: float, stop: asyncio.Event, traffic: Traffic) -> None:
    await asyncio.sleep(delay)
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        while not stop.is_set():
            data = await reader.read(65536)
            if not data:
                break
            traffic.state_bytes += len(data)
    finally:
        writer.close()


def clients(nice: int, ports: Sequence[str]) -> None:
    """``bench_fleet.py --clients NICE [DELAY:MOTION:STATE ...]``: until SIGTERM; SIGUSR1
    zeroes the counts, SIGUSR2 prints them (``stats {json}``)."""
    if nice:
        os.nice(nice)
    traffic = Traffic()

    def report() -> None:
        print("stats " + json.dumps(traffic.__dict__), flush=True)

    def reset() -> None:
        traffic.points = traffic.requests = traffic.state_bytes = 0

    async def main() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        loop.add_signal_handler(signal.SIGTERM, stop.set)
        loop.add_signal_handler(signal.SIGUSR1, reset)
        loop.add_signal_handler(signal.SIGUSR2, report)
        async with asyncio.TaskGroup() as tg:
            for entry in ports:
                delay, motion, state = entry.split(":")
                tg.create_task(stream(int(motion), float(delay), stop, traffic))
                tg.create_task(read_state(int(state), float(delay), stop, traffic))
            print("streaming", flush=True)

    asyncio.run(main())


# --------------------------------------------------------------------------- the driver


class Child:
    """A child process whose stdout lines are read with a timeout (never a blocking wait)."""

    def __init__(self, argv: list[str], nice: int = 0) -> None:
        cmd = ["nice", "-n", str(nice), *argv] if nice else argv
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE)  # noqa: S603 - our own argv
        assert self.proc.stdout is not None
        self._fd = self.proc.stdout.fileno()
        self._buffer = b""

    @property
    def pid(self) -> int:
        return self.proc.pid

    def line(self, timeout: float) -> str:
        end = time.monotonic() + timeout
        while b"\n" not in self._buffer:
            left = end - time.monotonic()
            if left <= 0 or not select.select([self._fd], [], [], left)[0]:
                raise SystemExit(
                    f"process {self.proc.args} said nothing for {timeout:.0f} s: the machine "
                    "is too loaded to start or answer it; run again when it is quieter"
                )
            chunk = os.read(self._fd, 65536)
            if not chunk:
                raise SystemExit(f"process {self.proc.args} ended (exit {self.proc.poll()})")
            self._buffer += chunk
        line, _, self._buffer = self._buffer.partition(b"\n")
        return line.decode()

    def stats(self) -> dict[str, Any]:
        """Ask for the stats line (SIGUSR2) and read it, skipping anything else printed."""
        self.proc.send_signal(signal.SIGUSR2)
        end = time.monotonic() + STATS_TIMEOUT_S
        while True:
            line = self.line(max(0.1, end - time.monotonic()))
            if line.startswith("stats "):
                result: dict[str, Any] = json.loads(line.removeprefix("stats "))
                return result

    def stop(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            self.proc.send_signal(signal.SIGTERM)

    def wait(self) -> None:
        try:
            self.proc.wait(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=STOP_TIMEOUT_S)


def me(*args: str) -> list[str]:
    return [sys.executable, str(Path(__file__).resolve()), *args]


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime


def machine_jiffies() -> list[int]:
    """/proc/stat's ``cpu`` line: user nice system idle iowait irq softirq steal ..."""
    with open("/proc/stat", encoding="ascii") as f:
        return [int(x) for x in f.readline().split()[1:9]]


def pct(sorted_samples: np.ndarray, q: float) -> float:
    """Nearest-rank percentile of sorted samples (as the ticker's)."""
    return float(sorted_samples[max(1, math.ceil(q * len(sorted_samples))) - 1])


@dataclass
class Setup:
    duration: float
    warmup: float
    client_procs: int
    client_nice: int
    realtime: bool
    probe: bool
    tmp: Path


def measure(name: str, setup: Setup) -> dict[str, Any]:
    """Start the arrangement ``name``, load it, measure it, stop it."""
    match = ARRANGEMENT.fullmatch(name)
    if match is None:
        raise SystemExit(f"arrangement {name!r}: write PxC (16x1, 4x4) or floorPxC (floor16x1)")
    kind = "floor" if match.group(1) else "twin"
    procs, per = int(match.group(2)), int(match.group(3))
    capacity = int((setup.duration + setup.warmup + 10.0) / PERIOD_S)
    samples = [setup.tmp / f"{name}-{i}.npy" for i in range(procs)]
    rt = ["--rt"] if setup.realtime else []
    servers: list[Child] = []
    loaders: list[Child] = []
    probe: Child | None = None
    probe_path = setup.tmp / f"{name}-probe.npy"
    t_start = time.monotonic()
    try:
        for path in samples:
            servers.append(Child(me("--serve", kind, str(per), str(capacity), str(path), *rt)))
        if setup.probe and kind == "twin":  # one do-nothing ticker, nobody connected to it
            probe = Child(me("--serve", "floor", "1", str(capacity), str(probe_path), *rt))
        deadline = t_start + READY_TIMEOUT_S
        if probe is not None:
            probe.line(max(0.1, deadline - time.monotonic()))
        ports: list[tuple[int, int]] = []
        for server in servers:
            for _ in range(per):
                line = server.line(max(0.1, deadline - time.monotonic()))
                ready = READY.fullmatch(line.strip())
                if ready is None:
                    raise SystemExit(f"unexpected line from a served process: {line!r}")
                ports.append((int(ready.group(1)), int(ready.group(2))))
        started = time.monotonic() - t_start
        spread = STAGGER_S / len(ports)
        entries = [f"{i * spread:.4f}:{m}:{s}" for i, (m, s) in enumerate(ports)]
        k = max(1, min(setup.client_procs, len(entries)))
        for group in (entries[i::k] for i in range(k)):
            loaders.append(Child(me("--clients", str(setup.client_nice), *group)))
        deadline = time.monotonic() + READY_TIMEOUT_S
        for loader in loaders:
            if loader.line(max(0.1, deadline - time.monotonic())) != "streaming":
                raise SystemExit("a client process did not start")
        time.sleep(setup.warmup)
        probes = [probe] if probe is not None else []
        for child in (*servers, *probes, *loaders):
            child.proc.send_signal(signal.SIGUSR1)
        jiffies0 = machine_jiffies()
        cpu0 = [cpu_seconds(c.pid) for c in servers], [cpu_seconds(c.pid) for c in loaders]
        t0 = time.monotonic()
        time.sleep(setup.duration)
        elapsed = time.monotonic() - t0
        cpu1 = [cpu_seconds(c.pid) for c in servers], [cpu_seconds(c.pid) for c in loaders]
        jiffies1 = machine_jiffies()
        load = os.getloadavg()[0]
        server_stats = [s.stats() for s in servers]
        for child in probes:
            child.stats()
        traffic = [c.stats() for c in loaders]
    finally:
        # the clients first: the servers then see EOFs
        for group in (loaders, servers, [probe] if probe is not None else []):
            for child in group:
                child.stop()
            for child in group:
                child.wait()
    cells = procs * per
    rows = [np.load(path) for path in samples]  # (per, n) each
    if min(r.shape[1] for r in rows) == 0:
        raise SystemExit(f"{name}: a process sampled no tick in the window; is it ticking?")
    every = np.sort(np.concatenate([r.ravel() for r in rows])) * 1000.0
    cell_p99 = sorted(pct(np.sort(row) * 1000.0, 0.99) for r in rows for row in r)
    first = [pct(np.sort(r[0]) * 1000.0, 0.99) for r in rows]
    last = [pct(np.sort(r[-1]) * 1000.0, 0.99) for r in rows]
    in_place = np.sort(np.load(probe_path).ravel()) * 1000.0 if probe is not None else None
    delta = [b - a for a, b in zip(jiffies0, jiffies1, strict=True)]
    total = sum(delta) or 1
    return {
        "name": name,
        "cells": cells,
        "started_s": started,
        "ticks": int(every.size),
        "p50": pct(every, 0.50),
        "p99": pct(every, 0.99),
        "max": float(every[-1]),
        "p99_worst_cell": cell_p99[-1],
        "p99_median_cell": cell_p99[len(cell_p99) // 2],
        "p99_first": sum(first) / len(first),
        "p99_last": sum(last) / len(last),
        "probe_p99": pct(in_place, 0.99) if in_place is not None and in_place.size else None,
        "overruns": sum(s["overruns"] for s in server_stats),
        "cpu_per_cell": 100.0 * sum(map(float.__sub__, cpu1[0], cpu0[0])) / elapsed / cells,
        "cpu_clients": 100.0 * sum(map(float.__sub__, cpu1[1], cpu0[1])) / elapsed,
        "busy": 100.0 * (total - delta[3] - delta[4]) / total,
        "steal": 100.0 * delta[7] / total,
        "load": load,
        "points": sum(t["points"] for t in traffic) / elapsed / cells,
        "requests": sum(t["requests"] for t in traffic) / elapsed / cells,
        "state_kb": sum(t["state_bytes"] for t in traffic) / elapsed / cells / 1000.0,
    }


HEADER: Final = (
    "arrangement  cells  lateness p50 / p99 / max ms  p99 worst/median cell  "
    "p99 first/last  probe p99  overruns  CPU/cell %  clients %  busy %  steal %  load  "
    "per cell: points/s  req/s  state kB/s  started in s"
)


def row(r: dict[str, Any]) -> str:
    ok = "ok  " if r["p99"] <= BUDGET_MS else "OVER"
    probe = "-" if r["probe_p99"] is None else f"{r['probe_p99']:.3f}"
    return (
        f"{r['name']:11s}  {r['cells']:5d}  {r['p50']:6.3f} / {r['p99']:6.3f} / {r['max']:6.1f} "
        f"{ok}  {r['p99_worst_cell']:6.3f} / {r['p99_median_cell']:6.3f}      "
        f"{r['p99_first']:6.3f} / {r['p99_last']:6.3f}  {probe:>9s}  {r['overruns']:8d}  "
        f"{r['cpu_per_cell']:10.1f}  {r['cpu_clients']:9.0f}  {r['busy']:6.0f}  "
        f"{r['steal']:7.1f}  {r['load']:4.1f}  {r['points']:18.1f}  {r['requests']:5.0f}  "
        f"{r['state_kb']:10.1f}  {r['started_s']:12.1f}"
    )


def main() -> None:
    if sys.argv[1:2] == ["--serve"]:
        kind, cells, capacity, path = sys.argv[2:6]
        serve(kind, int(cells), int(capacity), Path(path), "--rt" in sys.argv[6:])
        return
    if sys.argv[1:2] == ["--clients"]:
        clients(int(sys.argv[2]), sys.argv[3:])
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--arrangements",
        nargs="+",
        default=["16x1", "8x2", "4x4", "2x8", "floor16x1"],
        help="PxC: P processes of C cells; floorPxC: the do-nothing floor (default: %(default)s)",
    )
    parser.add_argument("--duration", type=float, default=20.0, help="seconds measured each")
    parser.add_argument("--warmup", type=float, default=3.0, help="seconds before (>= 1)")
    parser.add_argument("--client-procs", type=int, default=2, help="client processes")
    parser.add_argument(
        "--client-nice",
        type=int,
        default=19,
        help="their niceness (default %(default)s, as issue 13's recorded fleet figures; "
        "0: the clients compete with the cells at the same priority)",
    )
    parser.add_argument(
        "--realtime", action="store_true", help="every served process as `sim --realtime`"
    )
    parser.add_argument(
        "--no-probe",
        action="store_true",
        help="no do-nothing ticker beside each twin arrangement (see the docstring)",
    )
    parser.add_argument(
        "--rounds",
        type=int,
        default=1,
        help="measure every arrangement this many times, alternating, then the best p99 of "
        "each (default %(default)s)",
    )
    args = parser.parse_args()
    if args.rounds < 1 or args.duration <= 0 or args.client_procs < 1:
        parser.error("--rounds, --duration and --client-procs must be positive")
    if args.warmup < STAGGER_S:
        parser.error(f"--warmup must cover the clients' staggered start ({STAGGER_S} s)")
    for name in args.arrangements:
        match = ARRANGEMENT.fullmatch(name)
        if match is None or int(match.group(2)) < 1 or int(match.group(3)) < 1:
            parser.error(
                f"arrangement {name!r}: write PxC (16x1, 4x4) or floorPxC (floor16x1), "
                "P and C at least 1"
            )
    print(
        f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}, load average "
        f"{os.getloadavg()[0]:.2f} at start; {args.duration:.0f} s each after {args.warmup:.0f} s; "
        f"{args.client_procs} client processes at nice {args.client_nice}"
        + ("; served processes with --realtime" if args.realtime else ""),
        flush=True,
    )
    print(HEADER, flush=True)
    with tempfile.TemporaryDirectory(prefix="bench-fleet-") as tmp:
        setup = Setup(
            args.duration,
            args.warmup,
            args.client_procs,
            args.client_nice,
            args.realtime,
            not args.no_probe,
            Path(tmp),
        )
        best: dict[str, dict[str, Any]] = {}
        for _ in range(args.rounds):
            for name in args.arrangements:
                r = measure(name, setup)
                print(row(r), flush=True)
                if name not in best or r["p99"] < best[name]["p99"]:
                    best[name] = r
    if args.rounds > 1:
        print(f"best of {args.rounds} rounds (lowest pooled p99):")
        for r in best.values():
            print(row(r))
    print(f"load average {os.getloadavg()[0]:.2f} at the end (other work on the machine)")


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):
        main()
