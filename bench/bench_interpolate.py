"""Whole-process speed of ``pymotoros interpolate`` on a large CSV (issue 13; prints numbers).

    python bench/bench_interpolate.py                # 150,000 rows, points every 20 ms
    python bench/bench_interpolate.py --spacing-ms 4

Writes a 150,000-row 6-axis trajectory CSV (a sine on every joint, numbers at full
precision), then times, side by side and ``--repeat`` times each (best kept):

* ``python -m pymotoros interpolate TRAJ -o OUT`` as a process (large files go through
  pyarrow's CSV reader and writer);
* the same process with the Python csv module path forced (the code before issue 13),
  as the baseline;

and checks the two outputs are byte for byte the same. The rate is axis-increments
(output rows × axes) per second of the whole process, start-up included. The new
path's best run is split into phases from the command's own clock marks
(``PYMOTOROS_INTERPOLATE_TIMINGS``): interpreter start-up and imports, reading, the
plausibility check, the engine, the writing left after the engine (the writer thread
works while the engine computes), and the exit. ``uptime``'s load average is printed
before and after: on a busy machine the wall times are the machine's, not the code's.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FORCE_PYTHON = (
    "import sys, pymotoros.cli.interpolate as m; m.FAST_CSV_BYTES = 1 << 62; "
    "from pymotoros.cli.main import main; sys.argv = ['pymotoros', *sys.argv[1:]]; main()"
)


def write_trajectory(path: Path, rows: int, spacing_ms: int) -> None:
    """A slow sine on every joint, velocities consistent with it."""
    w = 2 * math.pi / 20.0
    with path.open("w", encoding="utf-8") as f:
        f.write("time,p1,p2,p3,p4,p5,p6,v1,v2,v3,v4,v5,v6\n")
        for k in range(rows):
            t = k * spacing_ms / 1000
            amp = [0.3 * (1 + 0.1 * i) for i in range(6)]
            pos = [a * (1 - math.cos(w * t)) for a in amp]
            vel = [a * w * math.sin(w * t) for a in amp]
            f.write(",".join(repr(x) for x in [t, *pos, *vel]) + "\n")


PHASES = ("start", "read", "check", "engine", "written")
PHASE_NAMES = (
    "interpreter + imports",
    "read CSV",
    "plausibility check",
    "engine",
    "write (after engine)",
)


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(argv: list[str]) -> tuple[float, dict[str, float]]:
    """Wall time of one process, and its phase marks relative to the launch (plus
    ``cpu``: its user + system CPU seconds, all threads)."""
    env = {**os.environ, "PYMOTOROS_INTERPOLATE_TIMINGS": "1"}
    cpu0 = children_cpu()
    t0 = time.monotonic()  # CLOCK_MONOTONIC: the clock of the child's marks too
    done = subprocess.run(  # noqa: S603 - our own argv
        argv, check=True, timeout=600, env=env, capture_output=True, text=True
    )
    wall = time.monotonic() - t0
    marks = {}
    found = re.search(r"interpolate timings monotonic: (.*)", done.stderr)
    if found:
        for item in found.group(1).split():
            name, _, value = item.partition("=")
            marks[name] = float(value) - t0
    marks["cpu"] = children_cpu() - cpu0
    return wall, marks


def split(wall: float, marks: dict[str, float]) -> str:
    """One line per phase: seconds and share of the whole process."""
    if not all(name in marks for name in PHASES):
        return "    (no timing marks: a pymotoros without PYMOTOROS_INTERPOLATE_TIMINGS)"
    lines, before = [], 0.0
    for name, label in zip(PHASES, PHASE_NAMES, strict=True):
        lines.append(f"    {label:24s} {marks[name] - before:6.3f} s")
        before = marks[name]
    lines.append(f"    {'exit':24s} {wall - before:6.3f} s")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=150_000)
    parser.add_argument("--spacing-ms", type=int, default=20)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(
        f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}, "
        f"load average {os.getloadavg()[0]:.2f} at start"
    )
    with tempfile.TemporaryDirectory() as tmp:
        traj = Path(tmp) / "traj.csv"
        write_trajectory(traj, args.rows, args.spacing_ms)
        fast_out, slow_out = Path(tmp) / "fast.csv", Path(tmp) / "slow.csv"
        fast_cmd = [
            sys.executable,
            "-m",
            "pymotoros",
            "interpolate",
            str(traj),
            "-o",
            str(fast_out),
        ]
        slow_cmd = [
            sys.executable,
            "-c",
            FORCE_PYTHON,
            "interpolate",
            str(traj),
            "-o",
            str(slow_out),
        ]
        fast_s: list[tuple[float, dict[str, float]]] = []
        slow_s: list[tuple[float, dict[str, float]]] = []
        for _ in range(args.repeat):
            fast_s.append(timed(fast_cmd))
            slow_s.append(timed(slow_cmd))
        same = fast_out.read_bytes() == slow_out.read_bytes()
        entries = sum(1 for _ in fast_out.open(encoding="utf-8")) - 1
        size = traj.stat().st_size / 1e6
    axis_increments = entries * 6
    print(
        f"{args.rows} rows ({size:.1f} MB), points every {args.spacing_ms} ms -> {entries} "
        f"queue entries ({axis_increments / 1e6:.2f} M axis-increments); best of {args.repeat}"
    )
    for name, runs in (("pyarrow CSV (now)", fast_s), ("Python csv (before)", slow_s)):
        walls = sorted(wall for wall, _ in runs)
        best = walls[0]
        cpu = min(marks["cpu"] for _, marks in runs)
        print(
            f"  {name:20s}: {best:.2f} s whole process, {axis_increments / best / 1e6:.2f} M/s "
            f"(median {walls[len(walls) // 2]:.2f} s; CPU {cpu:.2f} s, all threads)"
        )
    best_fast = min(fast_s, key=lambda run: run[0])
    print("  phases of the best pyarrow run:")
    print(split(*best_fast))
    print(f"  speed-up {min(s for s, _ in slow_s) / best_fast[0]:.2f}x; outputs identical: {same}")
    print(f"load average {os.getloadavg()[0]:.2f} at the end")
    if not same:
        raise SystemExit("the two paths disagree")


if __name__ == "__main__":
    main()
