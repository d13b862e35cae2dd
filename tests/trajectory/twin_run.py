"""Run a trajectory file on the in-memory twin and record what the servos executed."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pymotoros.cli.trajectory import client_trajectory
from pymotoros.client.errors import ReplyError
from pymotoros.models import robot_model
from pymotoros.testing import Twin, twin
from pymotoros.trajectory import Trajectory


@dataclass
class TwinOutcome:
    refused: ReplyError | None = None
    commands: list[list[tuple[int, ...]]] = field(default_factory=list)
    """Per tick, per group: the commanded pulses (8 slots) after the tick."""
    final: tuple[float, ...] = ()

    def increments(self, group: int, slots: Sequence[int]) -> np.ndarray:
        """Per-tick increments of ``group``'s ``slots``, without the still ticks around."""
        cmd = np.array([c[group] for c in self.commands], dtype=np.int64)[:, list(slots)]
        inc = np.diff(cmd, axis=0)
        moving = np.flatnonzero(np.any(inc != 0, axis=1))
        if not len(moving):
            return inc[:0]
        return inc[moving[0] : moving[-1] + 1]


def _record(tw: Twin, out: TwinOutcome) -> None:
    step = tw.clock._step
    assert step is not None
    servos = tw.controller._servos

    def recording() -> None:
        step()
        out.commands.append([tuple(s.command) for s in servos])

    tw.clock._step = recording


async def run_on_twin(
    traj: Trajectory, robot: str = "hc10", controller: str = "yrc1000"
) -> TwinOutcome:
    """Enable, stream exactly the file's points (no client pre-flight), wait until settled."""
    out = TwinOutcome()
    joint, groups = client_trajectory(traj, robot_model(robot))
    async with twin(robot=robot, controller=controller) as (client, tw):
        await client.start_trajectory_mode()
        _record(tw, out)
        try:
            result = await client.execute(joint, groups=groups, check_speed=False)
        except ReplyError as exc:
            out.refused = exc
        else:
            out.final = result.final_positions
        await tw.sleep(0.2)
    return out


async def twin_start(robot: str = "hc10", controller: str = "yrc1000") -> tuple[float, ...]:
    """Where the twin's robot stands after boot (every group, model order)."""
    async with twin(robot=robot, controller=controller) as (client, _):
        groups = tuple(range(len(client.robot.groups)))
        return await client.current_positions(groups)
