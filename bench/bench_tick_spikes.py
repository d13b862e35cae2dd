"""What the rare slow ticks of one streaming controller are (issue 13, item 3b).

``bench_cells.py`` shows one cell's tick, streaming, at p50 ~4 µs but p99.9 ~0.5 ms and a
max of 1-1.5 ms; with N cells in one loop those add up. This probe runs the same
no-socket loop (one HC10/YRC1000 streaming the sweep of ``bench_cells.py``) and, for
each tick, records its wall and thread time, the time spent in the interpolator's batch
computation (``GroupInterpolator._compute``, wrapped here) and any garbage collection
(``gc.callbacks``). It prints how much of the slow ticks each explains, then the same
statistics for a do-nothing loop and the hypervisor steal over the run (``/proc/stat``)
to tell the code from the machine.

``--paths`` runs the loop once per path, alternately, ``--rounds`` times, in one process:
``front`` (the queue's oldest segment computed alone when IncMove reaches it,
``GroupInterpolator._compute_front``, the controller's route since issue 13's second
round) and ``batch`` (every queued segment at once when the first is due, the route
before it: the front computation pointed at the all-at-once one for the run).

Usage: ``python bench/bench_tick_spikes.py [--ticks 10000] [--slow-us 200]
[--paths front batch] [--rounds 1]``
"""

from __future__ import annotations

import argparse
import gc
import os
import sys
import time
from typing import Any, Final

sys.path.insert(0, os.path.dirname(__file__))
from bench_runtime import sweep_point

from pymotoros.controller import VirtualController
from pymotoros.controller.api import Outcome, Pending, PointData
from pymotoros.motion import interpolator
from pymotoros.protocol.constants import MotionCommand, ResultCode

POINT_EVERY: Final = 2
"""As bench_cells.py's probe: the next point is offered every other tick."""
SWEEP_AMPLITUDE: Final = 0.5
SWEEP_PERIOD: Final = 4.0
"""The sweep of bench_cells.py (rad, s)."""
POINT_SPACING: Final = 0.1
"""Seconds between points (bench_cells.py's probe: 25 steps of 4 ms per segment)."""


def quantiles(values: list[float]) -> str:
    ordered = sorted(values)
    n = len(ordered)
    p50, p99, p999 = (ordered[min(n - 1, int(q * n))] for q in (0.5, 0.99, 0.999))
    return f"p50 {p50:.1f} µs, p99 {p99:.1f} µs, p99.9 {p999:.0f} µs, max {ordered[-1]:.0f} µs"


def steal_jiffies() -> int:
    """The steal column of /proc/stat's cpu line (0 where there is no /proc)."""
    try:
        with open("/proc/stat") as stat:
            fields = stat.readline().split()
    except OSError:
        return 0
    return int(fields[8]) if len(fields) > 8 else 0


PATHS: Final = ("front", "batch")
"""``front``: the controller's route (one segment per computation); ``batch``: every
queued segment at once."""
MAX_ROUNDS: Final = 20
"""Bound on --rounds (each round runs every path once)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=10_000, help="ticks to run (bounded)")
    parser.add_argument("--slow-us", type=float, default=200.0, help="a slow tick, µs")
    parser.add_argument(
        "--paths", nargs="+", choices=PATHS, default=list(PATHS), help="computation paths to run"
    )
    parser.add_argument("--rounds", type=int, default=1, help="times each path runs, alternately")
    args = parser.parse_args()
    if not 0 < args.ticks <= 1_000_000:
        raise SystemExit("--ticks must be between 1 and 1,000,000")
    if not 0 < args.rounds <= MAX_ROUNDS:
        raise SystemExit(f"--rounds must be between 1 and {MAX_ROUNDS}")
    for round_no in range(args.rounds):
        for path in args.paths:
            print(f"--- path {path}, round {round_no + 1} of {args.rounds}")
            run(args.ticks, args.slow_us, front=path == "front")


def run(ticks: int, slow_us: float, *, front: bool) -> None:
    """One streaming run of ``ticks`` ticks with the given computation path; prints."""
    tick_no = 0
    compute_us: dict[int, float] = {}
    batches: dict[int, int] = {}
    gc_us: dict[int, float] = {}
    gc_started = [0]
    gc_by_generation: dict[int, list[float]] = {}
    depth = [0]
    original = interpolator.GroupInterpolator._compute
    real_front = interpolator.GroupInterpolator._compute_front
    original_front = real_front if front else original  # batch: every queued segment at once

    def timed(self: interpolator.GroupInterpolator, method: Any) -> None:
        if depth[0]:  # _compute_front calling _compute: counted once, by the outer call
            method(self)
            return
        depth[0] += 1
        before_count = sum(s.count for s in self._uncomputed)
        before = time.perf_counter_ns()
        method(self)
        spent = (time.perf_counter_ns() - before) / 1e3
        entries = before_count - sum(s.count for s in self._uncomputed)
        compute_us[tick_no] = compute_us.get(tick_no, 0.0) + spent
        if entries:
            batches[tick_no] = batches.get(tick_no, 0) + entries
        depth[0] -= 1

    def timed_compute(self: interpolator.GroupInterpolator) -> None:
        timed(self, original)

    def timed_front(self: interpolator.GroupInterpolator) -> None:
        timed(self, original_front)

    def on_gc(phase: str, info: dict[str, Any]) -> None:
        if phase == "start":
            gc_started[0] = time.perf_counter_ns()
        else:
            spent = (time.perf_counter_ns() - gc_started[0]) / 1e3
            gc_by_generation.setdefault(info["generation"], []).append(spent)
            if tick_no >= 0:
                gc_us[tick_no] = gc_us.get(tick_no, 0.0) + spent

    interpolator.GroupInterpolator._compute = timed_compute  # type: ignore[method-assign]
    interpolator.GroupInterpolator._compute_front = timed_front  # type: ignore[method-assign]
    gc.callbacks.append(on_gc)
    controller = VirtualController()

    def resolve(request: Outcome | Pending) -> Outcome:
        while isinstance(request, Pending) and not request.done:
            controller.tick()
        return request.outcome if isinstance(request, Pending) else request

    controller.motion_connected()
    if (
        resolve(controller.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).result
        != ResultCode.SUCCESS
    ):
        raise SystemExit("START_TRAJ_MODE failed")
    steal0, load0 = steal_jiffies(), os.getloadavg()[0]
    seq, t = 0, 0.0
    wall: list[float] = []
    cpu: list[float] = []
    for k in range(ticks):
        tick_no = -1  # work outside tick() (the point offered) is not the tick's
        if k % POINT_EVERY == 0:
            p = sweep_point(seq, t, SWEEP_AMPLITUDE, SWEEP_PERIOD)
            data = PointData(0, p.valid_fields, p.time, tuple(p.pos), tuple(p.vel), tuple(p.acc))
            if resolve(controller.trajectory_point(seq, data)).result == ResultCode.SUCCESS:
                seq, t = seq + 1, t + POINT_SPACING
        tick_no = k
        w, c = time.perf_counter_ns(), time.thread_time_ns()
        controller.tick()
        cpu.append((time.thread_time_ns() - c) / 1e3)
        wall.append((time.perf_counter_ns() - w) / 1e3)
    gc.callbacks.remove(on_gc)
    interpolator.GroupInterpolator._compute = original  # type: ignore[method-assign]
    interpolator.GroupInterpolator._compute_front = real_front  # type: ignore[method-assign]

    idle: list[float] = []
    for _ in range(ticks):  # the same count of do-nothing "ticks"
        w = time.perf_counter_ns()
        idle.append((time.perf_counter_ns() - w) / 1e3)
    steal = steal_jiffies() - steal0

    slow = [k for k in range(ticks) if wall[k] > slow_us]
    in_batch = [k for k in slow if k in batches]
    in_gc = [k for k in slow if k in gc_us]
    neither = [k for k in slow if k not in batches and k not in gc_us]
    print(f"load average {load0:.2f} at start, {os.getloadavg()[0]:.2f} at end; {seq} points")
    print(f"tick wall   : {quantiles(wall)} ({ticks} ticks, no sockets)")
    print(f"tick thread : {quantiles(cpu)}")
    print(f"do-nothing  : {quantiles(idle)}")
    print(f"steal over the run: {steal} jiffies")
    sizes = sorted(batches.values())
    costs = sorted(compute_us[k] for k in batches)
    if costs:
        print(
            f"pulse computations in tick(): {len(costs)}, entries {sizes[0]}-{sizes[-1]}, "
            f"cost {quantiles(costs)}"
        )
    if gc_us:
        print(f"ticks with a GC: {len(gc_us)}, GC {quantiles(list(gc_us.values()))}")
    for generation, spent in sorted(gc_by_generation.items()):
        print(
            f"  generation-{generation} collections (in and out of ticks): {len(spent)}, "
            f"{quantiles(spent)}"
        )
    print(
        f"ticks over {slow_us:.0f} µs: {len(slow)}; with a pulse computation "
        f"{len(in_batch)}, with a GC {len(in_gc)}, with neither {len(neither)}"
    )
    for k in sorted(slow, key=lambda k: -wall[k])[:10]:
        print(
            f"  tick {k:6d}: wall {wall[k]:6.0f} µs, batch {compute_us.get(k, 0):6.0f} µs "
            f"({batches.get(k, 0)} entries), GC {gc_us.get(k, 0):6.0f} µs"
        )


if __name__ == "__main__":
    main()
