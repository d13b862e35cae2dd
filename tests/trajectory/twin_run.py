"""Run a trajectory file on the in-memory twin and record what the servos executed."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pymotoros.cli.trajectory_run import client_trajectory
from pymotoros.client.errors import ReplyError
from pymotoros.controller import CellConfig
from pymotoros.models import robot_model
from pymotoros.testing import Twin, twin
from pymotoros.trajectory import Trajectory


@dataclass
class TwinOutcome:
    refused: ReplyError | None = None
    commands: list[list[tuple[int, ...]]] = field(default_factory=list)
    """Per group, the commanded pulses (8 slots): before the first recorded tick, then
    after each tick."""
    executed: list[bool] = field(default_factory=list)
    """Per recorded tick: whether IncMove executed a queue entry in it (zero pulses
    included)."""
    final: tuple[float, ...] = ()
    period_ms: int = 0

    def _ticks(self, group: int, slots: Sequence[int]) -> np.ndarray:
        cmd = np.array([c[group] for c in self.commands], dtype=np.int64)[:, list(slots)]
        return np.diff(cmd, axis=0)

    def increments(self, group: int, slots: Sequence[int]) -> np.ndarray:
        """Per-tick increments of ``group``'s ``slots``, without the still ticks around."""
        inc = self._ticks(group, slots)
        moving = np.flatnonzero(np.any(inc != 0, axis=1))
        if not len(moving):
            return inc[:0]
        return inc[moving[0] : moving[-1] + 1]

    def executed_increments(self, group: int, slots: Sequence[int]) -> np.ndarray:
        """Per-tick increments from the first to the last tick that executed a queue
        entry (zero increments included): the whole motion as the twin ran it."""
        ticks = np.flatnonzero(self.executed)
        if not len(ticks):
            return self._ticks(group, slots)[:0]
        return self._ticks(group, slots)[ticks[0] : ticks[-1] + 1]

    @property
    def executed_ticks(self) -> int:
        """Ticks from the first to the last that executed a queue entry, both included:
        the motion's length as the twin runs it (``check``'s ``increments``)."""
        ticks = np.flatnonzero(self.executed)
        return int(ticks[-1] - ticks[0] + 1) if len(ticks) else 0

    @property
    def paused_ticks(self) -> int:
        """Ticks within the motion that executed nothing (the queue ran dry)."""
        return self.executed_ticks - int(sum(self.executed))

    @property
    def duration_s(self) -> float:
        return self.executed_ticks * self.period_ms / 1000.0


def _record(tw: Twin, out: TwinOutcome) -> None:
    """Record every tick from now on, through the twin's public tick hook."""
    groups = range(tw.controller.num_groups)
    out.period_ms = tw.controller.period_ms
    out.commands.append([tw.commanded_pulses(g) for g in groups])

    def recording() -> None:
        out.commands.append([tw.commanded_pulses(g) for g in groups])
        out.executed.append(tw.executed_this_tick())

    tw.on_tick(recording)


async def run_on_twin(
    traj: Trajectory,
    robot: str = "hc10",
    controller: str = "yrc1000",
    *,
    cell: CellConfig | None = None,
) -> TwinOutcome:
    """Enable, stream exactly the file's points (no client pre-flight), wait until
    settled; on a twin of ``robot`` on ``controller``, or started with ``cell``."""
    out = TwinOutcome()
    if cell is None:
        joint, groups = client_trajectory(traj, robot_model(robot))
        started = twin(robot=robot, controller=controller)
    else:
        joint, groups = client_trajectory(traj, Twin(cell).robot)
        started = twin(cell=cell)
    async with started as (client, tw):
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
