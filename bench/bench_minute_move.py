"""The minute-long move of issue 8: a client streams over a minute of motion to the
in-memory twin (:func:`pymotoros.testing.twin`, HC10 on a YRC1000) in virtual time.

Prints, per round, the wall time, the process's CPU time and how many times faster than
real time the move ran (the move's own duration is the baseline, so the ratio is
comparable between noisy runs), then the median and the best. Issue 8 asks that such a
test take "well under a second"; this is where that is measured, not in a unit test.

    python bench/bench_minute_move.py [--rounds 7] [--spacing 0.1] [--busy-policy immediate]

``--busy-policy immediate`` streams as the client did before issue 22 (every point
offered at once, into a BUSY): the same motion, about two to four times the offers.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import time

from pymotoros.client.streaming import BusyPolicy
from pymotoros.testing import twin

GOAL = (1.0, 0.5, 0.3, 0.2, -1.0, 0.5)
SPEED_SCALE = 0.007
"""Slow enough that the planned move from the HC10's home lasts over 60 s."""


async def one_round(
    spacing_s: float, policy: BusyPolicy = BusyPolicy.PACED
) -> tuple[float, float, float, int, int]:
    """(wall s, CPU s, virtual s, points, offers) of one move, set-up excluded."""
    async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
        client.streamer.busy_policy = policy
        await client.enable()
        here = await client.current_positions()
        plan = client.plan(here, GOAL, speed_scale=SPEED_SCALE, sample_period=spacing_s)
        virtual_start = cell.clock.now()
        wall_start, cpu_start = time.perf_counter(), time.process_time()
        result = await client.execute(plan)
        wall, cpu = time.perf_counter() - wall_start, time.process_time() - cpu_start
        virtual = cell.clock.now() - virtual_start
        return wall, cpu, virtual, len(plan.points), result.stream.offers


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=7, help="moves to run (default 7)")
    parser.add_argument(
        "--spacing", type=float, default=0.1, help="seconds between points (default 0.1)"
    )
    parser.add_argument(
        "--busy-policy",
        choices=[p.value for p in BusyPolicy],
        default=BusyPolicy.PACED.value,
        help="when each point is first offered (default paced; immediate: before issue 22)",
    )
    args = parser.parse_args()
    policy = BusyPolicy(args.busy_policy)
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start")
    walls, cpus = [], []
    for k in range(1, args.rounds + 1):
        wall, cpu, virtual, points, offers = asyncio.run(one_round(args.spacing, policy))
        walls.append(wall)
        cpus.append(cpu)
        print(
            f"round {k}: {virtual:.1f} s of motion ({points} points, {offers / points:.2f}"
            f" offers per point) in {wall:.3f} s wall,"
            f" {cpu:.3f} s CPU: {virtual / wall:.0f}x real time"
            f" (load {os.getloadavg()[0]:.2f})"
        )
    print(
        f"median {statistics.median(walls):.3f} s wall, {statistics.median(cpus):.3f} s CPU;"
        f" best {min(walls):.3f} s wall, {min(cpus):.3f} s CPU"
    )


if __name__ == "__main__":
    main()
