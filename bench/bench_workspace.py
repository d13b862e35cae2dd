"""The workspace's costs (issue 21): the twin's contact check, ``check`` and ``plan --avoid``.

1. ``tick``: one HC10/YRC1000 streaming a sweep (no sockets, as ``bench_tick_spikes.py``)
   past ten obstacles, some a few centimetres from the arm, and the same cell without
   obstacles, alternately in one run: the tick's wall time with and without, and the
   time spent in the contact check itself (wrapped), per tick.
2. ``check``: the collision part of ``pymotoros check --config`` on a 60 s trajectory
   that swings back and forth past ten obstacles (the MotoROS check before it is timed
   on its own).
3. ``avoid``: ``plan --avoid`` of a typical detour (the arm swinging past a ball in its
   way), imports warmed up first (toppra loads SciPy and Matplotlib: seconds, once per
   process).

Usage: ``python bench/bench_workspace.py [--ticks 20000] [--rounds 3] [--only tick check avoid]``
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time
from typing import Any, Final

from pymotoros.controller import VirtualController
from pymotoros.controller.api import Outcome, Pending, PointData
from pymotoros.controller.cell import cell_from_dict
from pymotoros.kinematics.collision import world_for_cell
from pymotoros.models.cell import cell_models_from_dict
from pymotoros.protocol.constants import MotionCommand, ResultCode, ValidFields

L_TILT: Final = 0.6
"""The arm leans forward (L axis, rad) while S sweeps: its elbow and wrist pass the obstacles."""
SWEEP: Final = 1.6
"""S sweeps from −0.8 to +0.8 rad and back."""
SWEEP_PERIOD_S: Final = 4.0
POINT_SPACING_S: Final = 0.1
POINT_EVERY: Final = 2
START: Final = [-SWEEP / 2, L_TILT, 0.0, 0.0, 0.0, 0.0]

# ten obstacles: a table under the robot, a post and a fixture beside the sweep, a ball
# just above the elbow's arc, and six small parts on shelves around the cell
OBSTACLES: Final[list[dict[str, Any]]] = [
    {"name": "table", "box": [1.6, 1.2, 0.05], "xyz": [0.4, 0.0, -0.03]},
    {"name": "post", "cylinder": [0.05, 1.5], "xyz": [0.2, -1.0, 0.75]},
    {"name": "fixture", "box": [0.3, 0.4, 0.2], "xyz": [0.9, 0.0, 0.1]},
    {"name": "ball", "sphere": 0.08, "xyz": [0.5, 0.0, 1.0]},
    *(
        {
            "name": f"part{i}",
            "box": [0.1, 0.1, 0.1],
            "xyz": [1.1 * math.cos(a), 1.1 * math.sin(a), 0.4],
        }
        for i, a in enumerate((1.2, 1.8, 2.4, 3.0, -2.4, -1.8))
    ),
]


def _cell(obstacles: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "robot": {"model": "hc10"},
        "initial": {"joints": {"R1": START}},
        "workspace": {"obstacles": obstacles},
    }


def _point(seq: int, t: float) -> PointData:
    w = 2 * math.pi / SWEEP_PERIOD_S
    s = START[0] + SWEEP * (1 - math.cos(w * t)) / 2
    v = SWEEP * w * math.sin(w * t) / 2
    pos = (s, L_TILT, 0.0, 0.0, 0.0, 0.0)
    vel = (v, 0.0, 0.0, 0.0, 0.0, 0.0)
    fields = int(ValidFields.TIME | ValidFields.POSITION | ValidFields.VELOCITY)
    return PointData(0, fields, t, pos, vel, (0.0,) * 6)


def stream(obstacles: list[dict[str, Any]], ticks: int) -> dict[str, float]:
    """Stream the sweep for ``ticks`` ticks; wall time per tick and the contact check's."""
    controller = VirtualController(cell_from_dict(_cell(obstacles)))
    contact = controller._workspace.contact
    spent = [0.0]
    if contact is not None:
        original = contact.tick

        def timed(now_ms: int) -> None:
            t0 = time.perf_counter_ns()
            original(now_ms)
            spent[0] += time.perf_counter_ns() - t0

        contact.tick = timed  # type: ignore[method-assign]

    def resolve(request: Outcome | Pending) -> Outcome:
        while isinstance(request, Pending) and not request.done:
            controller.tick()
        return request.outcome if isinstance(request, Pending) else request

    controller.motion_connected()
    if (
        resolve(controller.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).result
        != ResultCode.SUCCESS
    ):
        raise SystemExit("START_TRAJ_MODE failed")
    seq, t = 0, 0.0
    wall: list[float] = []
    for k in range(ticks):
        if k % POINT_EVERY == 0 and (
            resolve(controller.trajectory_point(seq, _point(seq, t))).result == ResultCode.SUCCESS
        ):
            seq, t = seq + 1, t + POINT_SPACING_S
        w = time.perf_counter_ns()
        controller.tick()
        wall.append((time.perf_counter_ns() - w) / 1e3)
    if controller.workspace_contacts:
        raise SystemExit(f"the sweep touched something: {controller.workspace_contacts}")
    return {
        "mean_us": statistics.fmean(wall),
        "p50_us": statistics.median(wall),
        "check_us": spent[0] / 1e3 / ticks,
        "checks": float(contact.checks if contact is not None else 0),
    }


def bench_tick(ticks: int, rounds: int) -> None:
    print(f"--- contact check per tick: HC10 streaming a sweep, {ticks} ticks per run")
    for r in range(rounds):
        with_ = stream(OBSTACLES, ticks)
        without = stream([], ticks)
        print(
            f"round {r + 1}: 10 obstacles: tick mean {with_['mean_us']:.1f} µs, p50 "
            f"{with_['p50_us']:.1f} µs, of which the contact check {with_['check_us']:.2f} µs "
            f"per tick ({with_['checks']:.0f} full checks in {ticks} ticks) | no obstacles: "
            f"mean {without['mean_us']:.1f} µs, p50 {without['p50_us']:.1f} µs, check "
            f"{without['check_us']:.2f} µs"
        )


def bench_check(rounds: int) -> None:
    from pymotoros.trajectory.check import check_against_cell
    from pymotoros.trajectory.collisions import find_collisions
    from pymotoros.trajectory.planning import plan_waypoints

    cell = cell_models_from_dict(_cell(OBSTACLES))
    left, right = START, [SWEEP / 2, L_TILT, 0.0, 0.0, 0.0, 0.0]
    way = [left, right] * 16
    traj = plan_waypoints(way, cell.robot, cell.controller, velocity_scaling=0.5)
    while traj.duration < 60.0:
        way += [left, right]
        traj = plan_waypoints(way, cell.robot, cell.controller, velocity_scaling=0.5)
    print(f"--- check of a {traj.duration:.1f} s trajectory past 10 obstacles")
    world = world_for_cell(cell)
    probes = [0]
    probe = world.probe

    def counted(qs: Any) -> Any:
        probes[0] += 1
        return probe(qs)

    world.probe = counted  # type: ignore[method-assign]
    for r in range(rounds):
        probes[0] = 0
        t0 = time.perf_counter()
        report = check_against_cell(traj, cell)
        t1 = time.perf_counter()
        found = find_collisions(traj, cell, report.per_group, world)
        t2 = time.perf_counter()
        print(
            f"round {r + 1}: MotoROS check {t1 - t0:.3f} s, collisions {t2 - t1:.3f} s "
            f"({report.increments} increments, {probes[0]} full checks, {len(found)} collisions)"
        )


def bench_avoid(rounds: int) -> None:
    from pymotoros.trajectory.avoid import plan_avoiding
    from pymotoros.trajectory.planning import plan_waypoints

    ball = {"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75]}
    cell = cell_models_from_dict({"robot": {"model": "hc10"}, "workspace": {"obstacles": [ball]}})
    world = world_for_cell(cell)
    left, right = [-0.8, 0.6, 0, 0, 0, 0], [0.8, 0.6, 0, 0, 0, 0]
    plan_waypoints([left, right], cell.robot, cell.controller)  # imports: toppra, SciPy
    print("--- plan --avoid: HC10 swinging past a ball in its way (imports warm)")
    for r in range(rounds):
        t0 = time.perf_counter()
        traj = plan_avoiding([left, right], cell, world)
        print(
            f"round {r + 1}: {time.perf_counter() - t0:.3f} s, {len(traj.times)} points, "
            f"{traj.duration:.2f} s of motion"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=20_000, help="ticks per streaming run")
    parser.add_argument("--rounds", type=int, default=3, help="runs of each measurement")
    parser.add_argument(
        "--only", nargs="+", choices=("tick", "check", "avoid"), default=["tick", "check", "avoid"]
    )
    args = parser.parse_args()
    if not 0 < args.ticks <= 1_000_000 or not 0 < args.rounds <= 20:
        raise SystemExit("--ticks must be in 1..1,000,000 and --rounds in 1..20")
    print(f"load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} CPUs")
    if "tick" in args.only:
        bench_tick(args.ticks, args.rounds)
    if "check" in args.only:
        bench_check(args.rounds)
    if "avoid" in args.only:
        bench_avoid(args.rounds)
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
