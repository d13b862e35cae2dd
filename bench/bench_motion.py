"""Motion engine benchmarks: offline throughput and the cost of one simulated tick.

    python bench/bench_motion.py [--seconds 60] [--spacing-ms 100]

Prints the offline engine's axis-increments per second (target ≥ 10 million) and the
average cost of one tick of GroupInterpolator.fill + inc_move + the commanded-pulse
update for a 6-axis trajectory streamed as a client streams it (target: the whole
controller tick ≲ 8 µs, i.e. 500× faster than real time at 4 ms).
"""

from __future__ import annotations

import argparse
import logging
import platform
import time

import numpy as np

from pymotoros.models import controller_model, robot_model
from pymotoros.motion import (
    GroupAxes,
    GroupInterpolator,
    TrajPoint,
    add_pulses,
    inc_move,
    interpolate_arrays,
    to_pulses,
)


def trajectory(seconds: float, spacing_ms: float, axes: GroupAxes) -> tuple[np.ndarray, ...]:
    """A smooth, deterministic 6-axis trajectory within the HC10's speed limits."""
    t = np.arange(0.0, seconds + 1e-9, spacing_ms / 1000.0)
    n = axes.num_axes
    freq = np.linspace(0.05, 0.15, n)
    amp = np.array(axes.max_speed[:n]) * 0.8 / (2 * np.pi * freq)
    pos = amp * np.sin(2 * np.pi * freq * t[:, None])
    vel = amp * 2 * np.pi * freq * np.cos(2 * np.pi * freq * t[:, None])
    return t, pos, vel


def bench_offline(axes: GroupAxes, seconds: float, spacing_ms: float, repeat: int = 7) -> None:
    t, pos, vel = trajectory(seconds, spacing_ms, axes)
    best = float("inf")
    for _ in range(repeat):
        start = time.process_time()
        times, incs = interpolate_arrays(t, pos, vel, axes)
        best = min(best, time.process_time() - start)
    count = incs.size
    print(
        f"offline  {seconds:g} s, points every {spacing_ms:g} ms: {len(times)} entries × "
        f"{axes.num_axes} axes in {best * 1e3:.2f} ms = "
        f"{count / best / 1e6:.1f} M axis-increments/s"
    )


def bench_ticks(axes: GroupAxes, seconds: float, spacing_ms: float, repeat: int = 5) -> None:
    t, pos, vel = trajectory(seconds, spacing_ms, axes)
    points = [
        TrajPoint(float(t[i]), tuple(pos[i].tolist()), tuple(vel[i].tolist()))
        for i in range(len(t))
    ]
    best = float("inf")
    ticks = 0
    for _ in range(repeat):
        g = GroupInterpolator(axes)
        commanded = to_pulses(points[0].pos, axes)
        g.start(points[0], commanded)
        nxt = 1
        ticks = 0
        start = time.process_time()
        while True:
            if nxt < len(points) and not g.pending:
                g.set_pending(points[nxt])
                nxt += 1
            g.fill(True)
            out = inc_move((g,))
            ticks += 1
            if out is None:
                if nxt >= len(points) and not g.pending:
                    break
                continue
            commanded = add_pulses(commanded, out[0].pulses)
        best = min(best, time.process_time() - start)
    assert commanded == to_pulses(points[-1].pos, axes)
    per_tick = best / ticks
    print(
        f"ticks    {seconds:g} s, points every {spacing_ms:g} ms: {ticks} ticks in "
        f"{best * 1e3:.1f} ms = {per_tick * 1e6:.2f} µs per tick "
        f"({axes.period_ms / 1000 / per_tick:.0f}× real time for the motion part)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--spacing-ms", type=float, action="append")
    args = parser.parse_args()
    logging.disable(logging.WARNING)
    axes = GroupAxes.from_model(robot_model("hc10").groups[0], controller_model("yrc1000"))
    print(f"Python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    for spacing in args.spacing_ms or [100.0, 20.0, 4.0]:
        bench_offline(axes, args.seconds, spacing)
        bench_ticks(axes, args.seconds, spacing)


if __name__ == "__main__":
    main()
