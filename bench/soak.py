"""Soak: stream random valid trajectories for minutes against a twin (issue 13, item 9).

    python bench/soak.py                   # the documented run: 10 minutes
    python bench/soak.py --minutes 0.5     # a quick look

Not part of CI. One process: a twin (``SimulatorApp``, real clock, port 0) and its
clients on the same event loop: one motion client streaming random trajectories (a few
points at random spacing, 20–200 ms, each a random step of up to ±0.025 rad per joint from the last,
slow enough for every speed check, BUSY retried every 5 ms) and four state readers.

Checks and prints at the end:

* pulse drift: the commanded position minus (the start + the sum of every increment
  IncMove handed to the servos), per axis: must be all zero;
* resident memory growth (VmRSS after a one-minute warm-up vs the end): < 5 MB;
* file descriptors: the same count at the end as after the warm-up;
* the interpolation loop's lateness and overruns over the run.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_runtime import MotionClient, state_reader

import pymotoros.controller.incmove_task as incmove_task
from pymotoros.controller import VirtualController
from pymotoros.motion import Increment
from pymotoros.protocol.constants import MotionCommand, ResultCode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionCtrl
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig

RSS_BUDGET_KIB = 5 * 1024
"""Issue 13: RSS growth under 5 MB over the soak."""

WARMUP_S = 60.0
"""Memory and descriptors are compared from here (imports, caches and buffers settle)."""


def rss_kib() -> int:
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS in /proc/self/status")


def fds() -> int:
    return len(os.listdir("/proc/self/fd"))


class Executed:
    """Sums every increment IncMove hands over (wraps ``incmove_task.inc_move``)."""

    def __init__(self) -> None:
        self.total = [0] * 8
        self._real = incmove_task.inc_move

    def __enter__(self) -> Executed:
        def counting(groups: object) -> tuple[Increment, ...] | None:
            incs = self._real(groups)  # type: ignore[arg-type]
            if incs is not None:
                self.total = [a + b for a, b in zip(self.total, incs[0].pulses, strict=True)]
            return incs

        incmove_task.inc_move = counting  # type: ignore[assignment]
        return self

    def __exit__(self, *exc: object) -> None:
        incmove_task.inc_move = self._real


async def stream_random(
    client: MotionClient, app: SimulatorApp, rng: random.Random, stop: asyncio.Event
) -> int:
    vc = app.controller
    assert isinstance(vc, VirtualController)
    points = 0
    while not stop.is_set():
        here = list(vc.snapshot().groups[0].command_rad)[:6]
        seq, t = 0, 0.0
        trajectory = [(0.0, here)]
        for _ in range(rng.randint(2, 8)):
            t += rng.uniform(0.02, 0.2)
            target = [q + rng.uniform(-0.5, 0.5) * 0.05 for q in trajectory[-1][1]]
            trajectory.append((t, target))
        for t, pos in trajectory:
            while True:
                reply = await client.request(JointTrajPtFull.for_joints(0, seq, t, pos, [0.0] * 6))
                if reply.result == ResultCode.BUSY:
                    await asyncio.sleep(0.005)
                    continue
                if reply.result != ResultCode.SUCCESS:
                    raise SystemExit(f"point {seq} refused: {reply}")
                break
            seq += 1
            points += 1
        while vc.has_queued_motion() or vc.motoros.interpolators[0].pending:
            await app.ticker.wait_ticks(5)
    return points


async def soak(minutes: float, seed: int) -> None:
    vc = VirtualController()
    config = SimulatorConfig(
        host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=None
    )
    rng = random.Random(seed)
    with Executed() as executed:
        async with SimulatorApp(vc, config) as app:
            start = list(vc.snapshot().groups[0].command_pulse)
            stop = asyncio.Event()
            counts = [0]
            readers = [
                asyncio.create_task(state_reader(app.ports.state, stop, counts)) for _ in range(4)
            ]
            reader, writer = await asyncio.open_connection("127.0.0.1", app.ports.motion)
            client = MotionClient(reader, writer)
            reply = await client.request(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
            if reply.result != ResultCode.SUCCESS:
                raise SystemExit(f"START_TRAJ_MODE failed: {reply}")
            streamer = asyncio.create_task(stream_random(client, app, rng, stop))
            warm = min(WARMUP_S, minutes * 60 / 4)
            await asyncio.sleep(warm)
            rss0, fds0 = rss_kib(), fds()
            app.ticker.reset_stats()
            t0 = time.monotonic()
            await asyncio.sleep(minutes * 60 - warm)
            stop.set()
            points = await streamer
            for task in readers:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            writer.close()
            await writer.wait_closed()
            elapsed = time.monotonic() - t0
            rss1, fds1 = rss_kib(), fds()
            final = list(vc.snapshot().groups[0].command_pulse)
            stats = app.tick_stats()
    drift = [f - (s + e) for f, s, e in zip(final, start, executed.total, strict=False)]
    late = stats.lateness_ms
    print(
        f"soak {minutes:g} min (measured {elapsed:.0f} s after {warm:.0f} s warm-up), "
        f"seed {seed}: {points} points streamed, {counts[0] / 1e6:.1f} MB of state read"
    )
    print(f"  pulse drift per axis: {drift}  ({'zero' if not any(drift) else 'NOT ZERO'})")
    print(
        f"  RSS {rss0 / 1024:.1f} -> {rss1 / 1024:.1f} MiB (growth {(rss1 - rss0) / 1024:+.2f} MiB)"
    )
    print(f"  file descriptors {fds0} -> {fds1}")
    print(
        f"  loop: {stats.count} ticks, {stats.overruns} overruns, lateness p50 {late.p50:.3f} "
        f"ms, p99 {late.p99:.3f} ms, max {late.max:.1f} ms"
    )
    ok = not any(drift) and rss1 - rss0 < RSS_BUDGET_KIB and fds1 <= fds0
    print("PASS" if ok else "FAIL")
    if not ok:
        raise SystemExit(1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=13)
    args = parser.parse_args()
    asyncio.run(soak(args.minutes, args.seed))


if __name__ == "__main__":
    main()
