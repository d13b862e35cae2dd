"""The user's path (issue 22): a planned minute-long move through ``pymotoros.testing.twin``,
beside the controller alone on the very same points, in one run.

    python bench/bench_user_path.py                       # the recorded run
    python bench/bench_user_path.py --rounds 1 --spacings 0.1   # a quick look
    python bench/bench_user_path.py --breakdown           # + where the time goes

For each case (point spacing 100 ms, 20 ms and 4 ms on the default HC10/YRC1000 cell,
and 100 ms on the cell with an S1CxG register table,
``examples/cells/hc10_register_outputs.toml``) the move is planned once (the HC10's
home to a fixed goal, slow enough to last about 63 s), then, alternating round by
round:

* **user's path**: ``async with twin(cell=...)``, ``enable()``, ``execute(plan)``: the
  client, the MotoROS server handlers, the in-memory streams, the state stream and the
  virtual clock, as a user's CI test runs them (set-up excluded);
* **controller alone**: the same points offered to a ``VirtualController`` of the same
  cell in a plain loop (one offer per tick until accepted, as
  ``bench/bench_controller.py`` does), no client, no servers, no event loop.

Printed per case: × real time (the move's virtual duration over the wall time) of the
best and the median round, both ways, their ratio, and the CPU time. ``--breakdown``
adds one profiled round of the user's path per case: the profile's own time per layer
(controller and motion engine, servers, codec, client, the twin's virtual time and
streams, asyncio's loop), scaled to the unprofiled round's wall time, and the counts
that set the cost (ticks, state cycles, event-loop turns, motion requests, BUSY
answers). Profiling inflates small functions more than large ones, so the split is an
estimate; the × real-time figures are not profiled.
"""

from __future__ import annotations

import argparse
import asyncio
import cProfile
import os
import pstats
import statistics
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from pymotoros.client.planning import JointTrajectory
from pymotoros.controller import CellConfig, VirtualController, default_cell
from pymotoros.controller.api import Outcome, PointData
from pymotoros.controller.cell import load_cell
from pymotoros.protocol.constants import MotionCommand, ResultCode
from pymotoros.testing import twin

ROOT: Final = Path(__file__).resolve().parents[1]
REGISTER_CELL: Final = ROOT / "examples" / "cells" / "hc10_register_outputs.toml"
GOAL: Final = (1.0, 0.5, 0.3, 0.2, -1.0, 0.5)
SPEED_SCALE: Final = 0.007
"""Slow enough that the planned move from the HC10's home lasts over 60 s (as
``bench/bench_minute_move.py``)."""
TARGETS: Final = {
    ("default", 0.1): 500,
    ("default", 0.02): 500,
    ("default", 0.004): 200,
    ("registers", 0.1): 400,
}
"""Issue 22's targets, × real time of the user's path."""


@dataclass(frozen=True)
class Case:
    cell_name: str
    spacing: float

    def cell(self) -> CellConfig:
        return load_cell(REGISTER_CELL) if self.cell_name == "registers" else default_cell()

    @property
    def label(self) -> str:
        return f"{self.cell_name} cell, points every {self.spacing * 1000:g} ms"


@dataclass(frozen=True)
class Round:
    wall: float
    cpu: float
    virtual: float


async def _plan(case: Case) -> tuple[JointTrajectory, tuple[float, ...]]:
    async with twin(cell=case.cell(), timeout_s=2.0) as (client, _):
        here = tuple(await client.current_positions())
        return (
            client.plan(here, GOAL, speed_scale=SPEED_SCALE, sample_period=case.spacing),
            here,
        )


async def _user_round(case: Case, plan: JointTrajectory) -> Round:
    async with twin(cell=case.cell(), timeout_s=2.0) as (client, the_twin):
        await client.enable()
        virtual_start = the_twin.clock.now()
        wall, cpu = time.perf_counter(), time.process_time()
        await client.execute(plan)
        return Round(
            time.perf_counter() - wall,
            time.process_time() - cpu,
            the_twin.clock.now() - virtual_start,
        )


def user_round(case: Case, plan: JointTrajectory) -> Round:
    return asyncio.run(_user_round(case, plan))


def _points(plan: JointTrajectory) -> list[PointData]:
    pad = (0.0,) * 4
    return [
        PointData(
            0,
            7,
            p.time,
            (*p.positions, *pad),
            (*p.velocities, *pad),
            (*(p.accelerations or (0.0,) * 6), *pad),
        )
        for p in plan.points
    ]


def controller_round(case: Case, plan: JointTrajectory) -> Round:
    """The same points through the controller's own API in a plain loop."""
    vc = VirtualController(case.cell())
    vc.wait_for(vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
    points = _points(plan)
    busy = ResultCode.BUSY
    tick, submit, wait_for = vc.tick, vc.trajectory_point, vc.wait_for
    seq = 0
    ticks = 0
    wall, cpu = time.perf_counter(), time.process_time()
    while seq < len(points) or vc.has_queued_motion():
        if seq < len(points):
            outcome = submit(seq, points[seq])
            if not isinstance(outcome, Outcome):
                outcome = wait_for(outcome)
            if outcome.result != busy:
                if not outcome.ok:
                    raise RuntimeError(f"point {seq} refused: {outcome.detail}")
                seq += 1
        tick()
        ticks += 1
    return Round(
        time.perf_counter() - wall,
        time.process_time() - cpu,
        ticks * vc.period_ms / 1000.0,
    )


LAYERS: Final = (
    (
        "controller + motion engine",
        (
            "pymotoros/controller/",
            "pymotoros/motion/",
            "pymotoros/kinematics/",
            "pymotoros/models/",
        ),
    ),
    ("servers (runtime)", ("pymotoros/runtime/",)),
    ("codec (protocol)", ("pymotoros/protocol/",)),
    ("client", ("pymotoros/client/",)),
    ("virtual time + in-memory streams (testing)", ("pymotoros/testing.py",)),
    ("asyncio loop, tasks, streams", ("asyncio/",)),
)


def breakdown(case: Case, plan: JointTrajectory, wall: float) -> None:
    """One profiled round: the profile's own time per layer, scaled to ``wall``.

    Counts are of functions that never wait (cProfile counts every resumption of a
    coroutine as a call; ``_process`` answers without suspending)."""
    profile = cProfile.Profile()
    profile.enable()
    user_round(case, plan)
    profile.disable()
    stats = pstats.Stats(profile)
    own: dict[str, float] = {}
    counts: dict[str, int] = {}
    watched = {
        "controller/cycle.py:tick": "ticks",
        "runtime/state_server.py:build_cycle": "state cycles built",
        "base_events.py:_run_once": "event-loop turns",
        "runtime/motion_server.py:_process": "motion requests answered (offers included)",
        "protocol/framing.py:encode": "frames encoded",
    }
    for (path, _line, name), (_cc, calls, tottime, _ct, _callers) in stats.stats.items():  # type: ignore[attr-defined]
        layer = "other (numpy, builtins, stdlib)"
        for label, parts in LAYERS:
            if any(part in path for part in parts):
                layer = label
                break
        own[layer] = own.get(layer, 0.0) + tottime
        for key, what in watched.items():
            file, func = key.split(":")
            if path.endswith(file) and name == func:
                counts[what] = counts.get(what, 0) + calls
    total = sum(own.values())
    print(f"  where the time goes (profiled {total:.2f} s, scaled to {wall * 1000:.0f} ms):")
    for layer, seconds in sorted(own.items(), key=lambda kv: -kv[1]):
        print(
            f"    {layer:45s} {seconds / total * 100:5.1f} %"
            f"  ~{seconds / total * wall * 1000:6.0f} ms"
        )
    for what, n in counts.items():
        print(f"    {what:45s} {n:7d}  ~{wall / n * 1e6 if n else 0:7.1f} µs of the round each")


async def _wakeups(n: int) -> float:
    """Seconds per task wake-up: two tasks waking each other through futures ``n`` times."""
    loop = asyncio.get_running_loop()
    ping: list[asyncio.Future[None]] = [loop.create_future()]
    pong: list[asyncio.Future[None]] = [loop.create_future()]

    async def responder() -> None:
        for _ in range(n):
            await ping[0]
            ping[0] = loop.create_future()
            pong[0].set_result(None)

    task = asyncio.create_task(responder())
    await asyncio.sleep(0)  # the responder waits
    start = time.perf_counter()
    for _ in range(n):
        ping[0].set_result(None)
        await pong[0]
        pong[0] = loop.create_future()
    elapsed = time.perf_counter() - start
    await task
    return elapsed / (2 * n)


def wakeup_us(n: int = 50_000) -> float:
    """The asyncio floor of this machine: µs per task wake-up (best of three)."""
    return min(asyncio.run(_wakeups(n)) for _ in range(3)) * 1e6


async def _startup() -> float:
    """Seconds from nothing to a connected client that has its first state."""
    start = time.perf_counter()
    async with twin(robot="hc10", timeout_s=2.0):
        return time.perf_counter() - start


def startup_ms(rounds: int = 20) -> tuple[float, float]:
    """(median, best) ms of :func:`_startup`, after one warm-up (imports)."""
    asyncio.run(_startup())
    times = [asyncio.run(_startup()) * 1000 for _ in range(rounds)]
    return statistics.median(times), min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="rounds per case (default 3)")
    parser.add_argument(
        "--spacings",
        type=float,
        nargs="+",
        default=[0.1, 0.02, 0.004],
        help="point spacings on the default cell (s)",
    )
    parser.add_argument(
        "--no-registers", action="store_true", help="skip the register-output cell case"
    )
    parser.add_argument(
        "--breakdown",
        action="store_true",
        help="add one profiled round per case: where the time goes",
    )
    args = parser.parse_args()
    cases = [Case("default", s) for s in args.spacings]
    if not args.no_registers:
        cases.append(Case("registers", 0.1))
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start")
    print(
        f"{'case':42s} {'user best':>10s} {'median':>8s} {'alone best':>11s} {'median':>8s}"
        f" {'alone/user':>10s} {'target':>7s}"
    )
    for case in cases:
        plan, _ = asyncio.run(_plan(case))
        user: list[Round] = []
        alone: list[Round] = []
        for _ in range(args.rounds):
            user.append(user_round(case, plan))
            alone.append(controller_round(case, plan))
        ux = sorted(r.virtual / r.wall for r in user)
        ax = sorted(r.virtual / r.wall for r in alone)
        target = TARGETS.get((case.cell_name, case.spacing))
        print(
            f"{case.label:42s} {ux[-1]:9.0f}x {statistics.median(ux):7.0f}x"
            f" {ax[-1]:10.0f}x {statistics.median(ax):7.0f}x {ax[-1] / ux[-1]:9.1f}x"
            f" {f'{target}x' if target else '':>7s}"
        )
        best = min(user, key=lambda r: r.wall)
        print(
            f"  {len(plan.points)} points, {best.virtual:.1f} s of motion; user's path best"
            f" {best.wall * 1000:.0f} ms wall, {best.cpu * 1000:.0f} ms CPU"
            f" ({best.wall / len(plan.points) * 1e6:.0f} µs per point);"
            f" controller alone best {min(r.wall for r in alone) * 1000:.0f} ms"
        )
        if args.breakdown:
            breakdown(case, plan, best.wall)
    wake = wakeup_us()
    print(
        f"asyncio floor: {wake:.1f} µs per task wake-up; a state cycle needs at least two"
        f" (the client's reader, the clock's driver): {40 * 2 * wake / 1000:.2f} ms per"
        f" virtual second at 40 cycles/s, before any work"
    )
    median, best = startup_ms()
    print(f"twin start-up to a client with its first state: median {median:.2f} ms,"
          f" best {best:.2f} ms")
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
