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
(output rows × axes) per second of the whole process, start-up included.
"""

from __future__ import annotations

import argparse
import math
import os
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


def timed(argv: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, timeout=600)  # noqa: S603 - our own argv
    return time.perf_counter() - t0


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
        fast_s, slow_s = [], []
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
    for name, s in (("pyarrow CSV (now)", fast_s), ("Python csv (before)", slow_s)):
        best = min(s)
        print(f"  {name:20s}: {best:.2f} s whole process, {axis_increments / best / 1e6:.2f} M/s")
    print(f"  speed-up {min(slow_s) / min(fast_s):.2f}x; outputs identical: {same}")
    if not same:
        raise SystemExit("the two paths disagree")


if __name__ == "__main__":
    main()
