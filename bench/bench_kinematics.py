"""Kinematics and register outputs: IK solves per second, and the cost per tick of the
S1CxG register output functions.

1. Forward kinematics, Jacobian and inverse kinematics of several models on random
   reachable poses, the IK seeded 0.3 rad (σ) away from a solution (a client's Cartesian
   move seeds each solve with the previous one, far closer). Calls per second, best of
   ``--repeat``.
2. A 20 s trajectory streamed tick by tick (as bench_controller.py) to an HC10 cell
   without S1CxG table (baseline) and to the same cell with every register output
   function enabled (Cartesian command and feedback, both pulse functions, TCP speed,
   axis speeds and positions, command and feedback, all 4-byte), run in alternation;
   µs per ``tick()``, × real time, and the difference: the per-tick cost of the outputs.

Run: ``python bench/bench_kinematics.py [--repeat 5] [--seconds 20]``
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from pymotoros.controller import PointData, VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.kinematics import chain_for
from pymotoros.protocol.constants import MotionCommand, ResultCode

MODELS = ("hc10", "gp7", "sia20d")
POSES = 300
SPACING_S = 0.02


def ik_rates(model: str, repeat: int) -> tuple[float, float, float, int]:
    chain = chain_for(model)
    rng = np.random.default_rng(1)
    qs = [rng.uniform(chain.lower, chain.upper) * 0.9 for _ in range(POSES)]
    targets = [chain.fk(q) for q in qs]
    seeds = [np.clip(q + rng.normal(0, 0.3, q.shape), chain.lower, chain.upper) for q in qs]
    best_fk = best_j = best_ik = math.inf
    failures = 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        for q in qs:
            chain.fk(q)
        best_fk = min(best_fk, time.perf_counter() - t0)
        t0 = time.perf_counter()
        for q in qs:
            chain.jacobian(q)
        best_j = min(best_j, time.perf_counter() - t0)
        failures = 0
        t0 = time.perf_counter()
        for target, seed in zip(targets, seeds, strict=True):
            try:
                chain.ik(target, seed)
            except ValueError:
                failures += 1
        best_ik = min(best_ik, time.perf_counter() - t0)
    return POSES / best_fk, POSES / best_j, POSES / best_ik, failures


ALL_FUNCTIONS: dict[str, int] = (
    {"208": 1, "209": 1, "217": 1, "218": 1}
    | {str(210 + k): 100 + 2 * k for k in range(7)}
    | {str(219 + k): 120 + 2 * k for k in range(7)}
    | {"202": 63, "204": 63, "205": 63, "206": 0, "207": 0}
    | {str(1090 + k): 140 + 2 * k for k in range(6)}
    | {str(1120 + k): 160 + k for k in range(6)}
    | {"330": 2, "331": 170, "332": 2, "333": 172}
    | {"334": 2, "335": 2, "336": 2, "337": 2}
    | {str(1270 + k): 200 + 2 * k for k in range(6)}
    | {str(1280 + k): 220 + 2 * k for k in range(6)}
    | {str(1290 + k): 240 + 2 * k for k in range(6)}
    | {str(1300 + k): 260 + 2 * k for k in range(6)}
)


SEED_CELL: dict[str, int] = (
    {"217": 1, "218": 1}
    | {str(219 + k): 10 + 2 * k for k in range(7)}
    | {"332": 2, "333": 30, "335": 2, "337": 2}
    | {str(1280 + k): 40 + 2 * k for k in range(6)}
    | {str(1300 + k): 60 + 2 * k for k in range(6)}
)
"""What the seed 003 cell reads: feedback Cartesian position, TCP speed, axis speeds and
positions, all 4-byte."""


def trajectory(seconds: float) -> list[PointData]:
    n = round(seconds / SPACING_S)
    w = 2 * math.pi / seconds
    pts = []
    for k in range(n + 1):
        t = k * SPACING_S
        pos = [0.3 * (1 - math.cos(w * t)) * (1 + 0.1 * i) for i in range(6)]
        vel = [0.3 * w * math.sin(w * t) * (1 + 0.1 * i) for i in range(6)]
        pts.append(PointData(0, 7, t, (*pos, 0.0, 0.0, 0.0, 0.0), (*vel, 0.0, 0.0, 0.0, 0.0),
                             (0.0,) * 10))  # fmt: skip
    return pts


def tick_cost(seconds: float, registers: dict[str, int] | None) -> float:
    """µs per tick (CPU time inside tick()) while the trajectory streams."""
    group: dict[str, object] = {"robot": "hc10"}
    if registers:
        group["s1cxg"] = registers
    vc = VirtualController(cell_from_dict({"groups": [group]}))
    vc.wait_for(vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
    points = trajectory(seconds)
    clock = time.process_time
    spent = 0.0
    ticks = seq = 0
    while seq < len(points) or vc.has_queued_motion():
        if seq < len(points):
            outcome = vc.wait_for(vc.trajectory_point(seq, points[seq]))
            if outcome.result != ResultCode.BUSY:
                seq += 1
        t0 = clock()
        vc.tick()
        spent += clock() - t0
        ticks += 1
    return spent / ticks * 1e6


def idle_cost(ticks: int, registers: dict[str, int] | None) -> float:
    """µs per tick of a robot at rest with servo on (the common case between moves)."""
    group: dict[str, object] = {"robot": "hc10"}
    if registers:
        group["s1cxg"] = registers
    vc = VirtualController(cell_from_dict({"groups": [group], "initial": {"servo": True}}))
    vc.run_ticks(200)
    t0 = time.process_time()
    vc.run_ticks(ticks)
    return (time.process_time() - t0) / ticks * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=20.0)
    args = parser.parse_args()
    print(f"kinematics, {POSES} random poses, best of {args.repeat}")
    print(f"{'model':>8} {'FK/s':>9} {'Jacobian/s':>11} {'IK/s':>8} {'IK failures':>12}")
    for model in MODELS:
        fk, jac, ik, failures = ik_rates(model, args.repeat)
        print(f"{model:>8} {fk:>9.0f} {jac:>11.0f} {ik:>8.0f} {failures:>12}")
    print(f"\nregister outputs: {args.seconds:g} s HC10 trajectory, points every 20 ms, "
          f"best of {args.repeat}, alternating")  # fmt: skip
    base = full = seed = math.inf
    for _ in range(args.repeat):
        base = min(base, tick_cost(args.seconds, None))
        seed = min(seed, tick_cost(args.seconds, SEED_CELL))
        full = min(full, tick_cost(args.seconds, ALL_FUNCTIONS))
    period_us = 4000.0
    idle_base = min(idle_cost(5000, None) for _ in range(args.repeat))
    idle_full = min(idle_cost(5000, ALL_FUNCTIONS) for _ in range(args.repeat))
    print(
        f"  at rest: {idle_base:.2f} µs/tick without a table, {idle_full:.2f} with every function"
    )
    print(f"  no S1CxG table:          {base:7.2f} µs/tick  {period_us / base:6.0f}× real time")
    for label, cost in (("the seed cell's outputs:", seed), ("every function enabled: ", full)):
        print(
            f"  {label} {cost:7.2f} µs/tick  {period_us / cost:6.0f}× real time"
            f"  (outputs {cost - base:.2f} µs/tick)"
        )


if __name__ == "__main__":
    main()
