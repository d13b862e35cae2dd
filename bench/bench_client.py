"""Client benchmark: CHECK_QUEUE_CNT round trip and trajectory streaming rate.

Starts ``pymotoros sim`` on 127.0.0.1 port 0 (or uses a controller given with --host and
the port options) and prints:

* the round trip of CHECK_QUEUE_CNT (request → echoed reply), p50 / p99 / max;
* how many trajectory points per second the client streams on a long move, for a 4 ms
  and a 20 ms point grid (MotoROS takes one point per interpolation tick and answers
  BUSY while its 200-entry queue is full, so the rate follows the robot's motion).

    python bench/bench_client.py [--requests 2000] [--host H --motion-port P ...]
"""

from __future__ import annotations

import argparse
import asyncio
import re
import statistics
import sys
import time

from pymotoros.client import RobotClient

_READY = re.compile(r"motion=(\d+) state=(\d+) io=(\d+)")


def _percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


async def round_trips(robot: RobotClient, count: int) -> list[float]:
    for _ in range(50):  # warm up
        await robot.queue_count()
    samples = []
    for _ in range(count):
        start = time.perf_counter()
        await robot.queue_count()
        samples.append(time.perf_counter() - start)
    return samples


async def stream_rate(robot: RobotClient, grid_s: float, distance: float) -> tuple[int, float, int]:
    here = await robot.current_positions()
    goal = (here[0] + distance, *here[1:])
    traj = robot.plan(here, goal, speed_scale=0.5, sample_period=grid_s)
    result = await robot.execute(traj)
    return result.stream.points, result.stream.elapsed_s, result.stream.busy_replies


async def run(args: argparse.Namespace) -> None:
    options = {
        "motion_port": args.motion_port,
        "state_port": args.state_port,
        "io_port": args.io_port,
    }
    async with RobotClient(args.host, **options) as robot:
        await robot.wait_for_state()
        await robot.enable()
        rtt = await round_trips(robot, args.requests)
        ms = [x * 1000 for x in rtt]
        print(
            f"CHECK_QUEUE_CNT round trip over {len(ms)} requests: "
            f"p50 {statistics.median(ms):.3f} ms, p99 {_percentile(ms, 0.99):.3f} ms, "
            f"max {max(ms):.3f} ms"
        )
        for grid in (0.004, 0.02):
            points, elapsed, busy = await stream_rate(robot, grid, 2.0)
            print(
                f"streaming, {grid * 1000:.0f} ms grid: {points} points in {elapsed:.2f} s = "
                f"{points / elapsed:.0f} points/s ({busy} BUSY replies retried)"
            )
            await robot.move_named("home")


async def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--host", default=None, help="use a running controller (default: start sim)"
    )
    parser.add_argument("--motion-port", type=int, default=50240)
    parser.add_argument("--state-port", type=int, default=50241)
    parser.add_argument("--io-port", type=int, default=50242)
    parser.add_argument("--requests", type=int, default=2000)
    args = parser.parse_args()
    if args.host is not None:
        await run(args)
        return
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "pymotoros", "sim", "--motion-port", "0", "--state-port", "0",
        "--io-port", "0", "--http-port", "0", stdout=asyncio.subprocess.PIPE,
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        async with asyncio.timeout(30):
            line = (await proc.stdout.readline()).decode()
        match = _READY.search(line)
        assert match is not None, line
        args.host = "127.0.0.1"
        args.motion_port, args.state_port, args.io_port = (int(x) for x in match.groups())
        await run(args)
    finally:
        proc.terminate()
        await proc.wait()


if __name__ == "__main__":
    asyncio.run(main())
