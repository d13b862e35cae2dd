"""The wire message of one trajectory point: JOINT_TRAJ_PT_FULL for one group,
MOTO_JOINT_TRAJ_PT_FULL_EX for several (one sequence number for all, reference §3.5).
"""

from __future__ import annotations

from collections.abc import Sequence

from pymotoros.client.planning import TrajectoryPoint
from pymotoros.protocol.constants import MsgType
from pymotoros.protocol.messages import (
    JointTrajPtExData,
    JointTrajPtFull,
    MotoJointTrajPtFullEx,
)


def _split(values: Sequence[float], sizes: Sequence[int]) -> list[tuple[float, ...]]:
    out, i = [], 0
    for n in sizes:
        out.append(tuple(values[i : i + n]))
        i += n
    return out


def build_message(
    point: TrajectoryPoint, sequence: int, groups: Sequence[int], sizes: Sequence[int]
) -> JointTrajPtFull | MotoJointTrajPtFullEx:
    """Type 14 for one group, 2016 for several (one sequence for all, §3.5)."""
    pos = _split(point.positions, sizes)
    vel = _split(point.velocities, sizes)
    acc = _split(point.accelerations, sizes) if point.accelerations else [None] * len(sizes)
    if len(groups) == 1:
        return JointTrajPtFull.for_joints(groups[0], sequence, point.time, pos[0], vel[0], acc[0])
    return MotoJointTrajPtFullEx.for_groups(
        sequence,
        [
            JointTrajPtExData.for_joints(g, point.time, p, v, a)
            for g, p, v, a in zip(groups, pos, vel, acc, strict=True)
        ],
    )


def message_type(groups: Sequence[int]) -> int:
    return int(
        MsgType.JOINT_TRAJ_PT_FULL if len(groups) == 1 else MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
    )
