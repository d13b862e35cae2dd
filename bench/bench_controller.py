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
* the wall time of the whole loop, point submissions and BUSY answers included;
* the controller alone: ticks with the increment queue filled directly (IncMove, servo,
  job, status monitor, no interpolation), to separate the motion engine's share.

Run: ``python bench/bench_controller.py [--seconds 60] [--repeat 3]``
"""

from __future__ import annotations

import argparse
import math
import time

from pymotoros.controller import PointData, VirtualController
from pymotoros.motion import QUEUE_SIZE, Increment
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


def run(seconds: float, spacing: float) -> tuple[int, float, float, float, int]:
    vc = VirtualController()
    vc.wait_for(vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
    points = trajectory(seconds, spacing)
    clock = time.perf_counter
    tick = vc.tick
    durations: list[float] = []
    record = durations.append
    ticks = 0
    seq = 0
    start = clock()
    max_ticks = int(seconds * 1000 / vc.period_ms) * 2 + 1000
    while seq < len(points) or vc.has_queued_motion():
        if seq < len(points):
            outcome = vc.wait_for(vc.trajectory_point(seq, points[seq]))
            if outcome.result != ResultCode.BUSY:
                if not outcome.ok:
                    raise RuntimeError(f"point {seq} refused: {outcome.detail}")
                seq += 1
        t0 = clock()
        tick()
        record(clock() - t0)
        ticks += 1
        if ticks > max_ticks:
            raise RuntimeError("the trajectory did not finish")
    total = clock() - start
    durations.sort()
    median = durations[len(durations) // 2]
    preempted = [d for d in durations if d > PREEMPTED_S]
    unpreempted = sum(durations) - sum(preempted) + median * len(preempted)
    return ticks, sum(durations), unpreempted, total, len(preempted)


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
    args = parser.parse_args()
    print(f"{args.seconds:g} s trajectory, 6 axes, HC10 on YRC1000, best of {args.repeat}")
    print(
        f"{'spacing':>8} {'ticks':>7} {'µs/tick':>8} {'× rt':>6} "
        f"{'unpreempted µs':>14} {'× rt':>6} {'(ticks >1ms)':>12} {'loop s':>7} {'× rt':>6}"
    )
    for spacing in args.spacings:
        runs = [run(args.seconds, spacing) for _ in range(args.repeat)]
        ticks, in_tick, trimmed, total, preempted = min(runs, key=lambda r: r[2])
        print(
            f"{spacing * 1000:>6.0f}ms {ticks:>7} {in_tick / ticks * 1e6:>8.2f} "
            f"{args.seconds / in_tick:>6.0f} {trimmed / ticks * 1e6:>14.2f} "
            f"{args.seconds / trimmed:>6.0f} {preempted:>12} "
            f"{total:>7.3f} {args.seconds / total:>6.0f}"
        )
    alone = controller_alone(15000)
    print(f"controller alone (queue pre-filled, no interpolation): {alone:.2f} µs/tick")


if __name__ == "__main__":
    main()
