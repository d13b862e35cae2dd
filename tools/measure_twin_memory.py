"""RSS and PSS of one ``pymotoros sim``, idle and while a client streams: the numbers
behind the requests and limits of deploy/k8s/statefulset.yaml (docs/fleet.md).

    python tools/measure_twin_memory.py            # prints a Markdown table
    python tools/measure_twin_memory.py --idle 20 --stream 30

The twin runs as in the image (control API on, a token, HC10 on YRC1000), on 127.0.0.1
and ports the OS picks. Its memory is read from /proc/PID/smaps_rollup (Rss, Pss,
Pss_Anon) and /proc/PID/status (VmHWM: the peak RSS) four times a second:

- idle: after ``--idle`` seconds with no client;
- streaming: for ``--stream`` seconds a client moves the robot back and forth
  (``pymotoros move``, one process per move: motion and state connections, trajectory
  streaming), while /metrics is scraped with the token once a second and
  ``pymotoros status`` asks the state port; the largest values seen.

A container's memory cgroup counts the process's resident pages (RSS, its shared
libraries included: nothing else in the pod shares them), so the request follows RSS;
PSS is what one more twin costs on a host where several share the libraries.
Linux only.
"""

from __future__ import annotations

import argparse
import json
import os
import secrets
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

FIELDS = ("Rss", "Pss", "Pss_Anon")


def sample(pid: int) -> dict[str, float]:
    """MiB of each field of smaps_rollup, and VmHWM."""
    out: dict[str, float] = {}
    for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
        key, _, rest = line.partition(":")
        if key in FIELDS:
            out[key] = int(rest.split()[0]) / 1024
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            out["VmHWM"] = int(line.split()[1]) / 1024
    return out


def peak(into: dict[str, float], values: dict[str, float]) -> None:
    for key, value in values.items():
        into[key] = max(into.get(key, 0.0), value)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--idle", type=float, default=20.0, help="seconds idle before sampling")
    parser.add_argument("--stream", type=float, default=30.0, help="seconds of streaming")
    args = parser.parse_args()
    token = secrets.token_urlsafe(32)
    env = {**os.environ, "PYMOTOROS_TOKEN": token}
    with tempfile.TemporaryDirectory() as tmp:
        ports_file = Path(tmp) / "ports.json"
        sim = subprocess.Popen(  # noqa: S603 - the package's own CLI
            [sys.executable, "-m", "pymotoros", "sim", "--motion-port", "0",
             "--state-port", "0", "--io-port", "0", "--http-port", "0",
             "--ports-file", str(ports_file)],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        try:
            ready = sim.stdout.readline() if sim.stdout is not None else ""
            if not ready.startswith("pymotoros sim ready"):
                raise SystemExit(f"pymotoros sim did not start: {ready!r}")
            http = json.loads(ports_file.read_text())["http"]
            time.sleep(args.idle)
            idle = sample(sim.pid)
            streaming: dict[str, float] = {}
            moves = 0
            pose = ["0.5", "0.3", "0.2", "0", "-0.5", "0"]
            home = ["0"] * 6
            deadline = time.monotonic() + args.stream
            cli = [sys.executable, "-m", "pymotoros"]
            where = ["--ports-file", str(ports_file)]
            scrape = urllib.request.Request(
                f"http://127.0.0.1:{http}/metrics", headers={"Authorization": f"Bearer {token}"}
            )
            while time.monotonic() < deadline:
                goal = pose if moves % 2 == 0 else home
                mover = subprocess.Popen(  # noqa: S603
                    [*cli, "move", "--enable", *where, *goal], env=env,
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                )  # fmt: skip
                while mover.poll() is None:
                    peak(streaming, sample(sim.pid))
                    time.sleep(0.25)
                if mover.returncode != 0:
                    raise SystemExit(f"pymotoros move exited {mover.returncode}")
                moves += 1
                with urllib.request.urlopen(scrape, timeout=5) as reply:  # noqa: S310
                    reply.read()
                subprocess.run([*cli, "status", *where], env=env, check=True,  # noqa: S603
                               stdout=subprocess.DEVNULL)  # fmt: skip
                peak(streaming, sample(sim.pid))
        finally:
            sim.terminate()
            sim.wait(timeout=30)
    sys.stdout.write(
        "| pymotoros sim (one twin, control API on) | RSS MiB | PSS MiB | PSS anon MiB |\n"
        "|---|---|---|---|\n"
        f"| idle {args.idle:.0f} s | {idle['Rss']:.1f} | {idle['Pss']:.1f} | "
        f"{idle['Pss_Anon']:.1f} |\n"
        f"| streaming ({moves} moves in {args.stream:.0f} s), largest | {streaming['Rss']:.1f} "
        f"| {streaming['Pss']:.1f} | {streaming['Pss_Anon']:.1f} |\n"
        f"| peak RSS over the run (VmHWM) | {streaming['VmHWM']:.1f} | | |\n"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
