"""Tick-by-tick speed of the virtual controller while a 6-axis trajectory streams.

A 60 s trajectory for the default cell (HC10 on YRC1000), every joint moving, sent
point by point as a client would: each point is offered once per tick until the
controller stops answering BUSY. The controller runs in virtual time, one
``tick()`` per 4 ms interpolation period, until the queue has drained.

Prints, for each point spacing, the best of ``--repeat`` runs:

* ticks, and the wall time spent inside ``tick()`` (µs per tick, and × real time);
* the same with every tick longer than 1 ms counted at the median tick time instead
  ("unpreempted"): no tick does 1 ms of work (the costliest, a new segment's
  interpolation, takes a few hundred µs at most); on a busy machine those are the ticks
  during which the process lost the CPU. The number of such ticks is printed;
* "intake": the time answering the points that were accepted, and "work" = ``tick()``
  + intake, the figure of issue 13 item 4 (≥ 500× real time is ≤ 8 µs per tick); the
  BUSY retries are the client's polling and are shown apart (µs per BUSY answer);
* the wall time of the whole loop, point submissions and BUSY answers included, and
  the process's CPU time for it (immune to preemption on a busy machine);
* the controller alone: ticks with the increment queue filled directly (IncMove, servo,
  job, status monitor, no interpolation), to separate the motion engine's share.

Each spacing runs the controller as it is ("fast") and, with ``--reference batch``,
alternating with it, the controller with every queued segment computed at once (see
:data:`PATHS`), with the ratio of the two. The controller has one route per rule
(issue 30); to compare with older code, run this file against that code's ``src``
(``PYTHONPATH=<old>/src``), alternating.

Run: ``python bench/bench_controller.py [--seconds 60] [--repeat 3] [--reference batch]``
"""

from __future__ import annotations

import argparse
import math
import os
import time
from typing import NamedTuple

from pymotoros.controller import PointData, VirtualController
from pymotoros.motion import QUEUE_SIZE, GroupInterpolator, Increment
from pymotoros.protocol.constants import MotionCommand, ResultCode


def trajectory(seconds: float, spacing: float) -> list[PointData]:
    """Every joint on a slow sine, starting and ending at rest at 0 rad."""
    n = round(seconds / spacing)
    pts = []
    for k in range(n + 1):
        t = k * spacing
        w = 2 * math.pi / seconds
        pos = [0.4 * (1 - math.cos(w * t)) * (1 + 0.1 * i) for i in range(6)]
        vel = [0.4 * w * math.sin(w * t) * (1 + 0.1 * i) for i in range(6)]
        pts.append(
            PointData(0, 7, t, (*pos, 0.0, 0.0, 0.0, 0.0), (*vel, 0.0, 0.0, 0.0, 0.0), (0.0,) * 10)
        )
    return pts


PREEMPTED_S = 0.001

PATHS = ("fast", "batch")
"""``fast``: the controller as it is. ``batch``: every queued segment computed at once
when the first is due (the queue's oldest segment not computed alone: the code before
issue 13's second round), by pointing the interpolator's front computation at its
all-at-once one for the run."""

_FRONT = GroupInterpolator._compute_front


def use_paths(paths: str) -> None:
    """Make interpolators made from now on compute as ``paths`` says (class-wide)."""
    GroupInterpolator._compute_front = (  # type: ignore[method-assign]
        GroupInterpolator._compute if paths == "batch" else _FRONT
    )


class Run(NamedTuple):
    ticks: int
    in_tick: float
    """Seconds inside ``tick()``."""
    unpreempted: float
    """The same with every tick over ``PREEMPTED_S`` counted at the median."""
    total: float
    """Seconds of the whole loop, BUSY answers included."""
    preempted: int
    intake: float
    """Seconds answering the points that were accepted (not the BUSY retries)."""
    busy: float
    """Seconds answering BUSY."""
    busy_count: int
    intake_unpreempted: float
    """``intake`` with every answer over ``PREEMPTED_S`` counted at the median."""
    cpu: float
    """CPU seconds of the process for the whole loop (immune to preemption, not to a
    busy machine's cache and memory contention)."""


def run(seconds: float, spacing: float, paths: str = "fast") -> Run:
    use_paths(paths)
    try:
        return _run(seconds, spacing)
    finally:
        use_paths("fast")


def _run(seconds: float, spacing: float) -> Run:
    vc = VirtualController()
    vc.wait_for(vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
    points = trajectory(seconds, spacing)
    clock = time.perf_counter
    tick = vc.tick
    submit = vc.trajectory_point
    busy_code = ResultCode.BUSY
    durations: list[float] = []
    record = durations.append
    ticks = 0
    seq = 0
    intake = busy = 0.0
    intake_times: list[float] = []
    busy_count = 0
    cpu_start = time.process_time()
    start = clock()
    max_ticks = int(seconds * 1000 / vc.period_ms) * 2 + 1000
    while seq < len(points) or vc.has_queued_motion():
        if seq < len(points):
            t0 = clock()
            result = submit(seq, points[seq])
            t1 = clock()
            outcome = vc.wait_for(result)
            if outcome.result == busy_code:
                busy += t1 - t0
                busy_count += 1
            else:
                if not outcome.ok:
                    raise RuntimeError(f"point {seq} refused: {outcome.detail}")
                intake += t1 - t0
                intake_times.append(t1 - t0)
                seq += 1
        t0 = clock()
        tick()
        record(clock() - t0)
        ticks += 1
        if ticks > max_ticks:
            raise RuntimeError("the trajectory did not finish")
    total = clock() - start
    cpu = time.process_time() - cpu_start
    in_tick = sum(durations)
    durations.sort()
    median = durations[len(durations) // 2]
    preempted = [d for d in durations if d > PREEMPTED_S]
    unpreempted = in_tick - sum(preempted) + median * len(preempted)
    intake_times.sort()
    intake_median = intake_times[len(intake_times) // 2]
    late = [d for d in intake_times if d > PREEMPTED_S]
    intake_unpreempted = intake - sum(late) + intake_median * len(late)
    return Run(
        ticks,
        in_tick,
        unpreempted,
        total,
        len(preempted),
        intake,
        busy,
        busy_count,
        intake_unpreempted,
        cpu,
    )


def controller_alone(ticks: int) -> float:
    """µs per tick with the queue pre-filled: IncMove, servo, job, monitor, no interpolation."""
    vc = VirtualController()
    vc.wait_for(vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
    queue = vc.motoros.interpolators[0].queue
    entry = (1, 2, 3, 4, 5, 6, 0, 0)

    class Prefilled:  # a "segment" whose entries are already computed
        def __init__(self, entries: list[Increment]) -> None:
            self.entries: list[Increment] | None = entries

    clock = time.perf_counter
    durations: list[float] = []
    while len(durations) < ticks:
        t0 = vc.time_ms
        batch = [Increment(t0 + 4 * (k + 1), entry, 0) for k in range(QUEUE_SIZE)]
        queue.add_lazy(Prefilled(batch), 0, QUEUE_SIZE)
        for _ in range(QUEUE_SIZE):
            start = clock()
            vc.tick()
            durations.append(clock() - start)
    durations.sort()
    median = durations[len(durations) // 2]
    kept = [d if d <= PREEMPTED_S else median for d in durations]
    return sum(kept) / len(kept) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--spacings", type=float, nargs="+", default=[0.1, 0.05, 0.02, 0.004], help="seconds"
    )
    parser.add_argument(
        "--reference",
        choices=[p for p in PATHS if p != "fast"],
        default=None,
        help="paths measured beside the controller's own, alternating (see PATHS)",
    )
    args = parser.parse_args()
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(
        f"{args.seconds:g} s trajectory, 6 axes, HC10 on YRC1000, best of {args.repeat}, "
        f"reference paths: {args.reference or 'none'}; load average {load}"
    )
    print(
        "work = tick() + answering the accepted points (the BUSY retries are the client's "
        "polling, shown apart); µs per tick, × real time"
    )
    print(
        f"{'spacing':>8} {'paths':>7} {'ticks':>6} {'tick()':>7} {'intake':>7} {'work':>6} "
        f"{'× rt':>5} {'unpre.':>7} {'× rt':>5} {'>1ms':>5} {'BUSY µs':>8} {'loop × rt':>9} "
        f"{'CPU × rt':>8}"
    )
    kinds = ("fast", args.reference) if args.reference else ("fast",)
    for spacing in args.spacings:
        best: dict[str, Run] = {}
        for _ in range(args.repeat):  # alternate, so both see the same machine
            for paths in kinds:
                r = run(args.seconds, spacing, paths)
                if paths not in best or r.unpreempted + r.intake_unpreempted < (
                    best[paths].unpreempted + best[paths].intake_unpreempted
                ):
                    best[paths] = r
        for paths in kinds:
            r = best[paths]
            work = r.in_tick + r.intake
            trimmed = r.unpreempted + r.intake_unpreempted
            busy_us = r.busy / r.busy_count * 1e6 if r.busy_count else 0.0
            print(
                f"{spacing * 1000:>6.0f}ms {paths:>7} {r.ticks:>6} "
                f"{r.in_tick / r.ticks * 1e6:>7.2f} {r.intake / r.ticks * 1e6:>7.2f} "
                f"{work / r.ticks * 1e6:>6.2f} {args.seconds / work:>5.0f} "
                f"{trimmed / r.ticks * 1e6:>7.2f} {args.seconds / trimmed:>5.0f} "
                f"{r.preempted:>5} {busy_us:>8.2f} {args.seconds / r.total:>9.0f} "
                f"{args.seconds / r.cpu:>8.0f}"
            )
        if not args.reference:
            continue
        fast, ref = best["fast"], best[args.reference]
        ratio = (ref.unpreempted + ref.intake_unpreempted) / (
            fast.unpreempted + fast.intake_unpreempted
        )
        print(
            f"{'':>8} fast is {ratio:.2f}× {args.reference} (unpreempted work), "
            f"{ref.cpu / fast.cpu:.2f}× (CPU time of the whole loop)"
        )
    alone = controller_alone(15000)
    print(f"controller alone (queue pre-filled, no interpolation): {alone:.2f} µs/tick")
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"load average at the end: {load}")


if __name__ == "__main__":
    main()
