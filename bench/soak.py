"""Soak: stream random valid trajectories for minutes against a twin (issues 13 and 23).

    python bench/soak.py                                # issue 13's run: 10 minutes
    python bench/soak.py --minutes 30 --spacing-ms 4 --io-poll-ms 50   # issue 23's run
    python bench/soak.py --minutes 0.5                  # a quick look

Not part of CI. One process: a twin (``SimulatorApp``, real clock, port 0) and its
clients on the same event loop: one motion client streaming random trajectories (a few
points at random spacing, 20–200 ms, each a random step of up to ±0.025 rad per joint from the last,
slow enough for every speed check, BUSY retried every 5 ms) and four state readers.
With ``--spacing-ms 4`` the motion client streams points 4 ms apart instead (sampled
cosine sweeps of joint 1, 2-6 s each, back to rest at the end, BUSY retried every
1 ms), the way a client streams a densely sampled plan. ``--io-poll-ms`` adds an IO
client reading an input bit at that period (0: none).

Every ``--sample-s`` seconds a line gives the resident memory, open descriptors and the
loop's lateness and overruns over that interval (the statistics are reset after each
line), so a leak or a drift shows as a trend, not only as an end-to-end difference.

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
import math
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
from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port, ResultCode
from pymotoros.protocol.framing import FrameDecoder, decode_reply, encode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionCtrl, MotoReadIoBit
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


async def stream_dense(
    client: MotionClient, app: SimulatorApp, rng: random.Random, stop: asyncio.Event, step: float
) -> int:
    """Cosine sweeps of joint 1 sampled every ``step`` s, each starting and ending at rest."""
    vc = app.controller
    assert isinstance(vc, VirtualController)
    points = 0
    while not stop.is_set():
        here = list(vc.snapshot().groups[0].command_rad)[:6]
        amplitude = rng.uniform(0.05, 0.3) * rng.choice((-1, 1))
        period = rng.uniform(2.0, 6.0)
        w = 2 * math.pi / period
        n = round(period / step)
        for seq in range(n + 1):
            t = seq * step
            pos = list(here)
            vel = [0.0] * 6
            pos[0] += amplitude * (1 - math.cos(w * t)) / 2
            vel[0] = amplitude * w * math.sin(w * t) / 2 if seq < n else 0.0
            if seq == n:
                pos[0] = here[0]
            while True:
                reply = await client.request(JointTrajPtFull.for_joints(0, seq, t, pos, vel))
                if reply.result == ResultCode.BUSY:
                    await asyncio.sleep(0.001)
                    continue
                if reply.result != ResultCode.SUCCESS:
                    raise SystemExit(f"point {seq} refused: {reply}")
                break
            points += 1
        while vc.has_queued_motion() or vc.motoros.interpolators[0].pending:
            await app.ticker.wait_ticks(5)
    return points


async def poll_io(port: int, period_s: float, stop: asyncio.Event, counts: list[int]) -> None:
    """Read input 10010 every ``period_s`` on the IO port (an HMI or PLC bridge)."""
    order = ByteOrder.LITTLE
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    decoder = FrameDecoder(order)
    try:
        while not stop.is_set():
            writer.write(encode(MotoReadIoBit(10010), order))
            while (frame := decoder.next_frame()) is None:
                data = await reader.read(4096)
                if not data:
                    return
                decoder.feed(data)
            decode_reply(frame, order, Port.IO)
            counts[1] += 1
            await asyncio.sleep(period_s)
    finally:
        writer.close()
        with contextlib.suppress(ConnectionError):
            await writer.wait_closed()


async def sample_over_time(
    app: SimulatorApp, every_s: float, stop: asyncio.Event, rows: list[tuple[float, ...]]
) -> None:
    """Every ``every_s``: (t, RSS MiB, fds, p50, p99, max lateness ms, overruns); then reset."""
    t0 = time.monotonic()
    while not stop.is_set():
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(every_s):
                await stop.wait()
        stats = app.tick_stats()
        late = stats.lateness_ms
        row = (
            time.monotonic() - t0,
            rss_kib() / 1024,
            float(fds()),
            late.p50,
            late.p99,
            late.max,
            float(stats.overruns),
        )
        rows.append(row)
        app.ticker.reset_stats()
        print(
            f"  t={row[0]:6.0f} s  RSS {row[1]:6.1f} MiB  fds {row[2]:3.0f}  lateness p50 "
            f"{row[3]:.3f} p99 {row[4]:.3f} max {row[5]:.1f} ms  overruns {row[6]:.0f}",
            flush=True,
        )


async def soak(
    minutes: float,
    seed: int,
    *,
    spacing_ms: float | None = None,
    io_poll_ms: float = 0.0,
    sample_s: float = 60.0,
) -> None:
    vc = VirtualController()
    config = SimulatorConfig(
        host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=None
    )
    rng = random.Random(seed)
    with Executed() as executed:
        async with SimulatorApp(vc, config) as app:
            start = list(vc.snapshot().groups[0].command_pulse)
            stop = asyncio.Event()
            counts = [0, 0]
            readers = [
                asyncio.create_task(state_reader(app.ports.state, stop, counts)) for _ in range(4)
            ]
            reader, writer = await asyncio.open_connection("127.0.0.1", app.ports.motion)
            client = MotionClient(reader, writer)
            reply = await client.request(MotoMotionCtrl(0, 0, MotionCommand.START_TRAJ_MODE))
            if reply.result != ResultCode.SUCCESS:
                raise SystemExit(f"START_TRAJ_MODE failed: {reply}")
            if spacing_ms is None:
                streamer = asyncio.create_task(stream_random(client, app, rng, stop))
            else:
                streamer = asyncio.create_task(
                    stream_dense(client, app, rng, stop, spacing_ms / 1000)
                )
            if io_poll_ms > 0:
                readers.append(
                    asyncio.create_task(poll_io(app.ports.io, io_poll_ms / 1000, stop, counts))
                )
            warm = min(WARMUP_S, minutes * 60 / 4)
            await asyncio.sleep(warm)
            rss0, fds0 = rss_kib(), fds()
            app.ticker.reset_stats()
            t0 = time.monotonic()
            rows: list[tuple[float, ...]] = []
            sampler = asyncio.create_task(sample_over_time(app, sample_s, stop, rows))
            await asyncio.sleep(minutes * 60 - warm)
            stop.set()
            points = await streamer
            await sampler
            for task in readers:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            writer.close()
            await writer.wait_closed()
            elapsed = time.monotonic() - t0
            rss1, fds1 = rss_kib(), fds()
            final = list(vc.snapshot().groups[0].command_pulse)
    drift = [f - (s + e) for f, s, e in zip(final, start, executed.total, strict=False)]
    mode = "random spacing" if spacing_ms is None else f"{spacing_ms:g} ms spacing"
    print(
        f"soak {minutes:g} min (measured {elapsed:.0f} s after {warm:.0f} s warm-up), "
        f"seed {seed}: {points} points streamed ({mode}), {counts[0] / 1e6:.1f} MB of state "
        f"read, {counts[1]} IO reads"
    )
    print(f"  pulse drift per axis: {drift}  ({'zero' if not any(drift) else 'NOT ZERO'})")
    print(
        f"  RSS {rss0 / 1024:.1f} -> {rss1 / 1024:.1f} MiB (growth {(rss1 - rss0) / 1024:+.2f} MiB)"
    )
    print(f"  file descriptors {fds0} -> {fds1}")
    if rows:
        half = max(1, len(rows) // 2)
        first = sorted(r[4] for r in rows[:half])[len(rows[:half]) // 2]
        last = sorted(r[4] for r in rows[half:] or rows)[len(rows[half:] or rows) // 2]
        print(
            f"  loop over {len(rows)} intervals: lateness p99 median {first:.3f} ms (first "
            f"half) vs {last:.3f} ms (second half), worst max {max(r[5] for r in rows):.1f} "
            f"ms, {sum(r[6] for r in rows):.0f} overruns; RSS min/max "
            f"{min(r[1] for r in rows):.1f}/{max(r[1] for r in rows):.1f} MiB"
        )
    ok = not any(drift) and rss1 - rss0 < RSS_BUDGET_KIB and fds1 <= fds0
    print("PASS" if ok else "FAIL")
    if not ok:
        raise SystemExit(1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=13)
    parser.add_argument(
        "--spacing-ms", type=float, default=None, help="stream points this far apart (e.g. 4)"
    )
    parser.add_argument("--io-poll-ms", type=float, default=0.0, help="IO read period (0: none)")
    parser.add_argument("--sample-s", type=float, default=60.0, help="time-series interval")
    args = parser.parse_args()
    asyncio.run(
        soak(
            args.minutes,
            args.seed,
            spacing_ms=args.spacing_ms,
            io_poll_ms=args.io_poll_ms,
            sample_s=args.sample_s,
        )
    )


if __name__ == "__main__":
    main()
