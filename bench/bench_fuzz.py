"""Fuzz benchmark: N mutated frames per MotoROS port against one twin (issue 23, item 3).

    python bench/bench_fuzz.py --frames 1000000   # the issue's run: a million per port
    python bench/bench_fuzz.py --frames 20000     # a quick look

Not part of CI (CI keeps ``tests/runtime/test_robustness.py`` at 10,000 per port). The
frames and connections are exactly those of that test (``fuzz_connection``: 1..200
framing-preserving mutations per connection in random chunks, sometimes a framing
break or a hanging half-frame, a FIN or an RST at the end), imported from it so the
benchmark and the test cannot drift apart. A frame counts on the motion and IO ports
when the *server* decoded it (its own request counter), on the state port when it was
written (the state server reads and drops what clients send, §2.3).

The attacker shares the twin's event loop and, like the test, waits one tick between
connections so its own work is not charged to the loop as lateness; the rate is
therefore the rate of this harness, a lower bound of what the servers take.

Printed per port: frames, seconds, frames/s; then the loop's skipped ticks, overruns and
lateness, RSS growth and file descriptors, whether a normal client was still served, and
PASS/FAIL (no error logged, descriptors back to the baseline, the loop within the test's
budget scaled to the count).
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import random
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))  # test helpers import load_proof by bare name

from tests.runtime.test_robustness import (  # noqa: E402 - the test's own fuzzer
    SEED,
    _fd_count,
    _rss_mib,
    assert_served,
    fuzz_connection,
    seeds,
    settle_fds,
)

from pymotoros.controller import VirtualController  # noqa: E402
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig  # noqa: E402

LOCAL = SimulatorConfig(host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=None)


class _Errors(logging.Handler):
    """Counts ERROR records (the servers log refused frames at INFO/WARNING only)."""

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.count = 0

    def emit(self, record: logging.LogRecord) -> None:
        self.count += 1


async def bench(frames: int, seed: int) -> bool:
    errors = _Errors()
    logging.getLogger().addHandler(errors)
    logging.getLogger().setLevel(logging.ERROR)
    rng = random.Random(seed)
    seed_frames = seeds()
    async with SimulatorApp(VirtualController(), LOCAL) as app:
        baseline_fds, rss0 = _fd_count(), _rss_mib()
        app.ticker.reset_stats()
        rows = []
        for name, port, decoded in (
            ("motion", app.ports.motion, lambda: app.motion.requests),
            ("io", app.ports.io, lambda: app.io.requests),
            ("state", app.ports.state, None),
        ):
            start_count = decoded() if decoded is not None else 0
            written = 0
            t0 = time.perf_counter()
            while (decoded() - start_count if decoded is not None else written) < frames:
                written += await fuzz_connection(rng, port, seed_frames)
                await app.ticker.wait_ticks(1)
            elapsed = time.perf_counter() - t0
            count = decoded() - start_count if decoded is not None else written
            rows.append((name, count, elapsed))
            print(
                f"  {name:6s} {count:>10,} frames in {elapsed:8.1f} s = {count / elapsed:>8,.0f}/s"
            )
        served = True
        try:
            await assert_served(app)
        except AssertionError:
            served = False
        await settle_fds(app, baseline_fds)
        stats = app.tick_stats()
        rss1 = _rss_mib()
    late = stats.lateness_ms
    total = sum(r[1] for r in rows)
    seconds = sum(r[2] for r in rows)
    per_port = {name: count / elapsed for name, count, elapsed in rows}
    print(
        f"total {total:,} frames in {seconds:.1f} s; a million per port would take "
        + ", ".join(f"{name} {1e6 / rate / 60:.1f} min" for name, rate in per_port.items())
    )
    print(
        f"loop: {stats.count} ticks, {stats.skipped} skipped, {stats.overruns} overruns, "
        f"lateness p50 {late.p50:.3f} ms p99 {late.p99:.3f} ms max {late.max:.1f} ms"
    )
    print(f"RSS {rss0:.1f} -> {rss1:.1f} MiB; fds back to {_fd_count()} (baseline {baseline_fds})")
    budget = 125 * max(1.0, frames / 10_000)  # the test's 125 ticks per 10,000 frames
    ok = served and errors.count == 0 and stats.skipped <= budget
    print(f"served after: {served}; errors logged: {errors.count}; " + ("PASS" if ok else "FAIL"))
    return ok


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1_000_000, help="frames per port")
    parser.add_argument("--seed", type=int, default=SEED)
    args = parser.parse_args()
    print(f"bench_fuzz: {args.frames:,} mutated frames per port, seed {args.seed}")
    if not asyncio.run(bench(args.frames, args.seed)):
        raise SystemExit(1)


if __name__ == "__main__":
    main()
