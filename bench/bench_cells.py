"""Several cells in one process: how many one core holds at lateness p99 <= 1 ms (issue 13,
item 3b; prints numbers, not a test).

    python bench/bench_cells.py                        # N = 1, 2, 4, ... (under 5 minutes)
    python bench/bench_cells.py --cells 1 8 --duration 5

For each N it starts one process running N cells (HC10 on YRC1000, each on its own
port-0 ports, one interpolation clock for all: ``runtime/fleet.py``, built and served by
the same functions as ``pymotoros sim --config ... --config ...``) and measures over
``--duration`` seconds, after ``--warmup``:

* idle: no client;
* streaming: every cell has its own motion client streaming a trajectory
  (JOINT_TRAJ_PT_FULL every 100 ms of trajectory time, BUSY retries every 5 ms, as the
  ROS driver does) and one state client; the clients run in a separate process at
  ``nice 19``, so that the load generator does not take the core from the cells. They
  start spread over 0.8 s, as independent clients would (``--aligned``: all at once, the
  worst case: identical trajectories then compute their next piece in the same tick).

Per N and mode: the process's CPU (utime + stime from /proc, % of one core), the loop's
lateness p50/p99/max and overruns (the first cell's tick), the step's duration p50/p99
(every cell's tick, in turn: the last cell ticks that much later) and "last cell p99",
the sum of the two p99s, which is what must stay within the budget. The series stops for
a mode once two sizes in a row miss the budget (one miss may be the machine's noise) or
the process uses a whole core (with ``--cells``, every N given is measured); the answer
is the largest N that met it, with the sizes that did not.

First, without sockets or the machine's noise: the CPU time of one cell's tick, idle and
streaming (``time.thread_time``, 10,000 ticks): what a step of N cells adds up, so what
the step durations would be on a quiet machine.

``--reference`` adds a third mode, ``streaming-batch``, right after each streaming run:
the same with every queued segment's pulses computed at once when the first is due
(the interpolator's front computation pointed at its all-at-once one for the run: the
route before issue 13's second round), so the two are compared side by side in one run.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Final

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import MotionClient, state_reader, sweep_point

from pymotoros.protocol.constants import MotionCommand, ResultCode
from pymotoros.protocol.messages import MotoMotionCtrl

CLK_TCK: Final = os.sysconf("SC_CLK_TCK")
BUDGET_MS: Final = 1.0
"""Issue 13: lateness p99 <= 1 ms."""
MISSES_TO_STOP: Final = 2
"""Sizes in a row over the budget that end a doubling series (one may be noise)."""
CORE_PCT: Final = 95.0
"""A process above this share of one core has no headroom left: the series stops."""
BUSY_RETRY_S: Final = 0.005
"""The ROS driver's retry interval after a BUSY reply (as bench_clock.py)."""
STAGGER_S: Final = 0.8
"""The streaming clients' starts are spread over this: one piece of segment (200 entries,
motion/interpolator.py ``PIECE_ENTRIES``, at 4 ms), so their piece computations spread
over the ticks instead of landing in one."""
STOP_TIMEOUT_S: Final = 30.0
CELL = Path(__file__).resolve().parents[1] / "examples" / "cells" / "hc10_yrc1000.toml"


# --------------------------------------------------------------------------- the cells' process


def serve(paths: list[Path], ports_file: Path, batch: bool = False) -> None:
    """The measured process: N cells served as ``pymotoros sim`` serves them. SIGUSR1
    resets the statistics (end of the warm-up); at SIGTERM it prints them as JSON.
    ``batch``: every queued segment computed at once (:func:`compute_all_at_once`)."""
    from pymotoros.cli.ports_file import CellLabel
    from pymotoros.cli.sim_cells import run_fleet
    from pymotoros.controller import VirtualController
    from pymotoros.controller.cell import load_cell
    from pymotoros.runtime.app import SimulatorConfig
    from pymotoros.runtime.fleet import Fleet, FleetCell, cell_names

    compute_all_at_once(batch)

    cells, labels = [], []
    for name, path in zip(cell_names(paths), paths, strict=True):
        cell = load_cell(path)
        config = SimulatorConfig(motion_port=0, state_port=0, io_port=0, http_port=0)
        cells.append(FleetCell(name, VirtualController(cell), config))
        labels.append(CellLabel.of(name, cell, path))
    fleet = Fleet(cells)

    async def main() -> None:
        asyncio.get_running_loop().add_signal_handler(signal.SIGUSR1, fleet.reset_stats)
        await run_fleet(fleet, labels, ports_file)

    asyncio.run(main())
    tick, step = fleet.tick_stats(), fleet.step_stats()
    counts = {c.controller.tick_count for c in cells}  # type: ignore[attr-defined]
    print(
        json.dumps(
            {
                "p50": tick.lateness_ms.p50,
                "p99": tick.lateness_ms.p99,
                "max": tick.lateness_ms.max,
                "overruns": tick.overruns,
                "skipped": tick.skipped,
                "step_p50": step.p50,
                "step_p99": step.p99,
                "step_max": step.max,
                "lockstep": len(counts) == 1,
            }
        ),
        flush=True,
    )


# --------------------------------------------------------------------------- the load generator


async def stream(port: int, stop: asyncio.Event, delay: float) -> int:
    """After ``delay`` s, stream a back-and-forth sweep of joint 1 until ``stop``; returns
    points sent."""
    await asyncio.sleep(delay)
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    client = MotionClient(reader, writer)
    reply = await client.request(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
    if reply.result != ResultCode.SUCCESS:
        raise SystemExit(f"START_TRAJ_MODE failed: {reply}")
    seq, t = 0, 0.0
    while not stop.is_set():
        reply = await client.request(sweep_point(seq, t, 0.5, 4.0))
        if reply.result == ResultCode.BUSY:
            await asyncio.sleep(BUSY_RETRY_S)
            continue
        if reply.result != ResultCode.SUCCESS:
            raise SystemExit(f"point {seq} refused: {reply}")
        seq, t = seq + 1, t + 0.1
    writer.close()
    return seq


def load(ports_file: Path, aligned: bool) -> None:
    """One motion and one state client per cell until SIGTERM; prints points sent.

    The clients start spread over :data:`STAGGER_S` (unless ``aligned``), as independent
    clients would: started together, identical trajectories make every cell compute its
    next piece of segment in the same tick (the worst case, ``--aligned``)."""

    data = json.loads(ports_file.read_text())
    entries = data.get("cells", [data])

    async def main() -> None:
        stop = asyncio.Event()
        asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, stop.set)
        counts = [0]
        async with asyncio.TaskGroup() as tg:
            spread = 0.0 if aligned else STAGGER_S / len(entries)
            streams = [
                tg.create_task(stream(e["motion"], stop, i * spread)) for i, e in enumerate(entries)
            ]
            for e in entries:
                tg.create_task(state_reader(e["state"], stop, counts))
            print("streaming", flush=True)
        print(json.dumps({"points": sum(s.result() for s in streams), "state_bytes": counts[0]}))

    asyncio.run(main())


# --------------------------------------------------------------------------- one tick's work


TICK_PROBE_TICKS: Final = 10_000
"""Ticks of the tick-cost probe (40 s of controller time, ~1 s to run)."""
TICK_PROBE_POINT_EVERY: Final = 2
"""The probe offers the next trajectory point every other tick (BUSY until it fits)."""


def tick_cost(streaming: bool, batch: bool = False) -> tuple[list[float], int]:
    """CPU time (thread time: not the time the OS gave to others) of each of
    :data:`TICK_PROBE_TICKS` ticks of one HC10/YRC1000, idle or streaming the same sweep as
    the clients, through the controller's API (no sockets), µs. Without the machine's
    noise, this is the work a step of N cells adds up. Also the points sent."""
    from pymotoros.controller import VirtualController
    from pymotoros.controller.api import Outcome, Pending, PointData

    compute_all_at_once(batch)
    controller = VirtualController()

    def resolve(request: Outcome | Pending) -> Outcome:
        while isinstance(request, Pending) and not request.done:
            controller.tick()
        return request.outcome if isinstance(request, Pending) else request

    if streaming:
        controller.motion_connected()
        start = resolve(controller.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
        if start.result != ResultCode.SUCCESS:
            raise SystemExit(f"START_TRAJ_MODE failed: {start}")
    seq, t, costs = 0, 0.0, []
    for k in range(TICK_PROBE_TICKS):
        if streaming and k % TICK_PROBE_POINT_EVERY == 0:
            p = sweep_point(seq, t, 0.5, 4.0)
            data = PointData(0, p.valid_fields, p.time, tuple(p.pos), tuple(p.vel), tuple(p.acc))
            if resolve(controller.trajectory_point(seq, data)).result == ResultCode.SUCCESS:
                seq, t = seq + 1, t + 0.1
        before = time.thread_time_ns()
        controller.tick()
        costs.append((time.thread_time_ns() - before) / 1000.0)
    compute_all_at_once(False)
    return costs, seq


_FRONT: list[object] = []


def compute_all_at_once(on: bool) -> None:
    """Interpolators made from now on compute every queued segment at once when the first
    is due (``on``) or the queue's oldest alone, as the controller does (off)."""
    from pymotoros.motion import GroupInterpolator

    if not _FRONT:
        _FRONT.append(GroupInterpolator._compute_front)
    GroupInterpolator._compute_front = (  # type: ignore[method-assign]
        GroupInterpolator._compute if on else _FRONT[0]
    )


def print_tick_cost(modes: tuple[str, ...]) -> None:
    for mode in modes:
        raw, points = tick_cost(mode.startswith("streaming"), batch=mode == "streaming-batch")
        costs = sorted(raw)
        n = len(costs)
        p50, p99, p999 = (costs[min(n - 1, int(q * n))] for q in (0.5, 0.99, 0.999))
        print(
            f"one cell's tick, CPU {mode:15s}: p50 {p50:.1f} µs, p99 {p99:.1f} µs, "
            f"p99.9 {p999:.0f} µs, max {costs[-1]:.0f} µs ({n} ticks, {points} points, no sockets)"
        )


# --------------------------------------------------------------------------- the driver


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat", encoding="ascii") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime


def me(*args: str, nice: int = 0) -> list[str]:
    cmd = [sys.executable, str(Path(__file__).resolve()), *args]
    return ["nice", "-n", str(nice), *cmd] if nice else cmd


def measure(
    n: int,
    streaming: bool,
    duration: float,
    warmup: float,
    tmp: Path,
    aligned: bool,
    batch: bool = False,
) -> dict[str, Any]:
    paths = []
    for i in range(n):
        path = tmp / f"cell{i:03d}.toml"
        path.write_text(CELL.read_text())
        paths.append(path)
    ports_file = tmp / f"ports-{n}.json"
    args = ["--serve", str(ports_file), *(["--batch"] if batch else []), *map(str, paths)]
    cells = subprocess.Popen(me(*args), stdout=subprocess.PIPE, text=True)  # noqa: S603
    assert cells.stdout is not None
    loadgen: subprocess.Popen[str] | None = None
    try:
        for _ in range(n):
            line = cells.stdout.readline()
            if not line.startswith("pymotoros sim ready"):
                raise SystemExit(f"no ready line from the cells' process: {line!r}")
        if streaming:
            loadgen = subprocess.Popen(  # noqa: S603
                me("--load", str(ports_file), *(["--aligned"] if aligned else []), nice=19),
                stdout=subprocess.PIPE,
                text=True,
            )
            assert loadgen.stdout is not None
            if loadgen.stdout.readline().strip() != "streaming":
                raise SystemExit("the load generator did not start")
        time.sleep(warmup)
        cells.send_signal(signal.SIGUSR1)
        cpu0, t0 = cpu_seconds(cells.pid), time.monotonic()
        time.sleep(duration)
        cpu1, elapsed = cpu_seconds(cells.pid), time.monotonic() - t0
        points = 0
        if loadgen is not None:
            loadgen.send_signal(signal.SIGTERM)
            out, _ = loadgen.communicate(timeout=STOP_TIMEOUT_S)
            points = json.loads(out.strip().splitlines()[-1])["points"]
        cells.send_signal(signal.SIGTERM)
        out, _ = cells.communicate(timeout=STOP_TIMEOUT_S)
        result: dict[str, Any] = json.loads(out.strip().splitlines()[-1])
    finally:
        for proc in (loadgen, cells):
            if proc is not None and proc.poll() is None:
                proc.kill()
                proc.wait(timeout=STOP_TIMEOUT_S)
    result["cpu"] = 100.0 * (cpu1 - cpu0) / elapsed
    result["points"] = points
    result["last"] = result["p99"] + result["step_p99"]
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, nargs="+", help="N to measure (default: doubling)")
    parser.add_argument("--max-cells", type=int, default=64, help="largest N when doubling")
    parser.add_argument("--duration", type=float, default=10.0, help="seconds per N and mode")
    parser.add_argument("--warmup", type=float, default=2.0)
    parser.add_argument(
        "--aligned", action="store_true", help="start every streaming client at once (worst case)"
    )
    parser.add_argument(
        "--reference",
        action="store_true",
        help="also stream with every queued segment computed at once (streaming-batch)",
    )
    parser.add_argument("--serve", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--batch", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--load", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("paths", type=Path, nargs="*", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve is not None:
        serve(args.paths, args.serve, args.batch)
        return
    if args.load is not None:
        load(args.load, args.aligned)
        return
    sizes = args.cells or [
        1 << k for k in range(args.max_cells.bit_length()) if 1 << k <= args.max_cells
    ]
    print(
        f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}, "
        f"load average {os.getloadavg()[0]:.2f} at start; {args.duration:.0f} s per N and mode"
    )
    modes = ("idle", "streaming", "streaming-batch") if args.reference else ("idle", "streaming")
    print_tick_cost(modes[1:])
    print(
        "   N  mode             CPU %  lateness p50/p99/max ms   overruns  step p50/p99 ms"
        "  last cell p99 ms  points"
    )
    best: dict[str, int] = {}
    missed: dict[str, list[int]] = {mode: [] for mode in modes}
    stopped: set[str] = set()
    with tempfile.TemporaryDirectory(prefix="bench-cells-") as tmp:
        for n in sizes:
            for mode in modes:
                if mode in stopped:
                    continue
                streaming = mode.startswith("streaming")
                batch = mode == "streaming-batch"
                r = measure(
                    n, streaming, args.duration, args.warmup, Path(tmp), args.aligned, batch
                )
                ok = r["last"] <= BUDGET_MS and r["cpu"] <= CORE_PCT
                print(
                    f"{n:4d}  {mode:15s} {r['cpu']:6.1f}  {r['p50']:6.3f} / {r['p99']:6.3f} / "
                    f"{r['max']:6.1f}  {r['overruns']:8d}  {r['step_p50']:6.3f} / "
                    f"{r['step_p99']:6.3f}  {r['last']:8.3f} {'ok ' if ok else 'OVER'}"
                    f"  {r['points']:6d}{'' if r['lockstep'] else '  NOT IN LOCKSTEP'}",
                    flush=True,
                )
                if ok:
                    best[mode] = n
                else:
                    missed[mode].append(n)
                # doubling: a saturated core, or misses at two sizes in a row, end the
                # series (one miss may be the machine's noise: the next size decides)
                recent = missed[mode][-MISSES_TO_STOP:]
                in_a_row = len(recent) == MISSES_TO_STOP and recent[0] * 2 == recent[-1]
                if not args.cells and (r["cpu"] > CORE_PCT or in_a_row):
                    stopped.add(mode)
            if stopped == set(modes):
                break
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    for mode in modes:
        held = best.get(mode)
        shown = f"{held}" if held else "none"
        over = f" (over the budget at N = {', '.join(map(str, missed[mode]))})"
        shown += over if missed[mode] else ""
        print(f"cells per core at p99 <= {BUDGET_MS:g} ms, {mode}: {shown}")


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):
        main()
