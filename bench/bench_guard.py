"""The cost of the client's workspace guard (issue 29 item 3): what checking a move
against the cell's obstacles adds before anything is sent (prints numbers, not a test).

    python bench/bench_guard.py [--rounds 5]

On ``examples/cells/hc10_table_fixture.toml`` (an HC10 on a table, a fixture, a post;
the gripper's shape on the flange): building the collision model once, then the best of
``--rounds`` of :meth:`Avoidance.check` for three clear moves (a joint move from the
boot pose to a ready pose, one above the fixture, a straight 100 mm descent) and for the
issue's move into the fixture (refused), each with its seconds of motion; last the wall
time of ``move_pose`` refusing that move on the in-memory twin (waiting for the robot at
rest included).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import math
import time
from pathlib import Path
from typing import Final

from pymotoros import PathBlockedError
from pymotoros.client.avoid import Avoidance
from pymotoros.client.cartesian import plan_linear_move
from pymotoros.client.planning import JointLimits, JointTrajectory, plan_joint_move
from pymotoros.client.tools import ToolTable
from pymotoros.controller.cell import load_cell
from pymotoros.models.cell import load_cell_models
from pymotoros.testing import Twin

CELL: Final = Path(__file__).resolve().parents[1] / "examples" / "cells" / "hc10_table_fixture.toml"
READY: Final = (0.0, 0.0, 1.047, 0.0, -1.047, 0.0)
ABOVE: Final = (0.70, 0.0, 0.10, math.pi, 0.0, 0.0)
INTO: Final = (0.70, 0.0, -0.10, math.pi, 0.0, 0.0)
TICK_S: Final = 0.004


def _best(avoidance: Avoidance, plan: JointTrajectory, rounds: int) -> float:
    best = math.inf
    for _ in range(rounds):
        start = time.perf_counter()
        with contextlib.suppress(PathBlockedError):
            avoidance.check(plan, [0], [None], TICK_S)
        best = min(best, time.perf_counter() - start)
    return best


async def _refusal_wall_s() -> float:
    async with Twin(load_cell(CELL)) as the_twin:
        client = the_twin.client(cell=load_cell_models(CELL), tool=0)
        await client.connect()
        await client.wait_for_state()
        await client.enable()
        start = time.perf_counter()
        with contextlib.suppress(PathBlockedError):
            await client.move_pose(INTO)
        took = time.perf_counter() - start
        await client.close()
        return took


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    cell = load_cell_models(CELL)
    tools = ToolTable(cell.robot, cell.tools)
    tools.use(0)
    avoidance = Avoidance(cell, tools)
    start = time.perf_counter()
    avoidance.world()
    print(f"collision model built in {(time.perf_counter() - start) * 1000:.0f} ms")
    limits = JointLimits.from_group(cell.robot.groups[0])
    chain = tools.chain(0)
    above = tuple(chain.ik(ABOVE, READY).q.tolist())
    lower = (ABOVE[0], ABOVE[1], ABOVE[2] - 0.1, *ABOVE[3:])
    cases = {
        "joint, boot pose -> ready (clear)": plan_joint_move([0.0] * 6, READY, limits),
        "joint, ready -> above the fixture (clear)": plan_joint_move(READY, above, limits),
        "straight 100 mm down above the fixture (clear)": plan_linear_move(
            chain, above, lower, limits
        ),
        "joint, boot pose -> into the fixture (refused)": plan_joint_move(
            [0.0] * 6, tuple(chain.ik(INTO, [0.0] * 6).q.tolist()), limits
        ),
    }
    for name, plan in cases.items():
        took = _best(avoidance, plan, args.rounds)
        print(f"{name}: {plan.duration:.2f} s of motion, checked in {took * 1000:.1f} ms")
    print(f"move_pose into the fixture refused in {asyncio.run(_refusal_wall_s()):.3f} s wall")


if __name__ == "__main__":
    main()
