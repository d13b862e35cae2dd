"""The run of a trajectory in a session recording, for ``pymotoros plot --recording``.

A recording (``--record``, ``sim --record``, or a Wireshark capture) holds the points
the client sent with the controller's replies, and the feedback of the state port.
The points are paired with their MOTO_MOTION_REPLY (MotoROS answers in order); BUSY
answers make the client resend, so only the SUCCESS one counts. Time 0 is that reply
to the start point (sequence 0). A recording may hold several trajectories: the one
with the file's number of points is used (the last such), else the last one, with a
warning. Errors are :class:`~pymotoros.cli.options.BadInput` (one line, exit 2).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from pymotoros.cli.options import BadInput
from pymotoros.models import RobotModel
from pymotoros.trajectory.files import Trajectory

if TYPE_CHECKING:
    from pymotoros.client.recording import Recording
    from pymotoros.trajectory.plot import RecordedRun, Series

Sample = tuple[float, tuple[float, ...]]
"""(time s, positions) of one feedback message of one group."""


@dataclass(frozen=True, slots=True)
class AcceptedPoint:
    """A trajectory point the controller answered SUCCESS to."""

    reply_time: float
    sequence: int
    groups: list[tuple[int, float, tuple[float, ...], tuple[float, ...]]]
    """(group, time, positions, velocities) of each group the point carries."""


def accepted_points(rec: Recording) -> list[AcceptedPoint]:
    """Every point the controller accepted, in order, over all motion connections."""
    from pymotoros.client.recording import Direction
    from pymotoros.protocol.constants import MsgType, Port, ResultCode
    from pymotoros.protocol.messages import (
        JointTrajPtFull,
        MotoJointTrajPtFullEx,
        MotoMotionReply,
    )

    point_types = {int(MsgType.JOINT_TRAJ_PT_FULL), int(MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX)}
    accepted = []
    for conn in rec.on(Port.MOTION):
        pending: list[Any] = []
        for m in conn.messages:
            msg = m.message
            if m.direction is Direction.TO_SERVER and msg is not None:
                pending.append(msg)
            elif isinstance(msg, MotoMotionReply) and pending:
                request = pending.pop(0)
                if msg.command not in point_types or msg.result != ResultCode.SUCCESS:
                    continue
                if isinstance(request, JointTrajPtFull):
                    records = [(request.group_no, request.time, request.pos, request.vel)]
                    accepted.append(AcceptedPoint(m.offset, request.sequence, records))
                elif isinstance(request, MotoJointTrajPtFullEx):
                    records = [(g.group_no, g.time, g.pos, g.vel) for g in request.groups]
                    accepted.append(AcceptedPoint(m.offset, request.sequence, records))
    return accepted


def choose_run(accepted: list[AcceptedPoint], points: int, path: Path) -> list[AcceptedPoint]:
    """The trajectory (a run from a sequence 0 on) of ``points`` points, the last such,
    else the last one recorded with a warning."""
    runs: list[list[AcceptedPoint]] = []
    for item in accepted:
        if item.sequence == 0 or not runs:
            runs.append([])
        runs[-1].append(item)
    if not runs:
        raise BadInput(
            f"--recording: {path} holds no trajectory point the controller accepted "
            "(record a `pymotoros run` with --record)"
        )
    matching = [r for r in runs if len(r) == points]
    if matching:
        return matching[-1]
    click.echo(
        f"warning: {path.name}: no trajectory of {points} points (the file's); "
        f"plotting the last one recorded ({len(runs[-1])} points)",
        err=True,
    )
    return runs[-1]


def commanded_series(chosen: list[AcceptedPoint], columns: dict[int, list[int]]) -> list[Series]:
    """One series per group of the points sent, times from the start point's."""
    from pymotoros.trajectory.plot import Series

    out = []
    for gi, cols in columns.items():
        n = len(cols)
        rows = [(t, p[:n], v[:n]) for point in chosen for g, t, p, v in point.groups if g == gi]
        if not rows:
            continue
        times = np.array([r[0] for r in rows], dtype=np.float64)
        out.append(
            Series(
                times - times[0],
                np.array([r[1] for r in rows], dtype=np.float64),
                tuple(cols),
                np.array([r[2] for r in rows], dtype=np.float64),
            )
        )
    return out


def feedback_series(rec: Recording, t0: float, columns: dict[int, list[int]]) -> list[Series]:
    """One series per group of the feedback, times from ``t0`` (the start accepted)."""
    from pymotoros.protocol.constants import Port
    from pymotoros.protocol.messages import JointFeedback, MotoJointFeedbackEx
    from pymotoros.trajectory.plot import Series

    single: dict[int, list[Sample]] = {}
    multi: dict[int, list[Sample]] = {}
    for conn in rec.on(Port.STATE):
        for m in conn.messages:
            msg = m.message
            if isinstance(msg, JointFeedback):
                single.setdefault(msg.group_no, []).append((m.offset - t0, msg.pos))
            elif isinstance(msg, MotoJointFeedbackEx):
                for g in msg.groups:
                    multi.setdefault(g.group_no, []).append((m.offset - t0, g.pos))
    out = []
    for gi, cols in columns.items():
        samples = single.get(gi) or multi.get(gi)  # MotoROS sends both for ≥ 2 groups
        if not samples:
            continue
        n = len(cols)
        out.append(
            Series(
                np.array([s[0] for s in samples], dtype=np.float64),
                np.array([s[1][:n] for s in samples], dtype=np.float64),
                tuple(cols),
            )
        )
    return out


def recorded_run(path: Path, traj: Trajectory, robot: RobotModel) -> RecordedRun:
    """The run of ``traj`` in the session recording at ``path`` (see the module)."""
    from pymotoros.client.recording import RecordingError, read_recording
    from pymotoros.trajectory.plot import RecordedRun

    try:
        rec = read_recording(path)
    except (RecordingError, OSError) as exc:
        raise BadInput(f"--recording: {exc}") from None
    chosen = choose_run(accepted_points(rec), len(traj.times), path)
    columns = dict(traj.group_columns(robot))
    commanded = commanded_series(chosen, columns)
    feedback = feedback_series(rec, chosen[0].reply_time, columns)
    if not feedback:
        click.echo(f"warning: {path.name}: no feedback of the file's groups recorded", err=True)
    return RecordedRun(tuple(commanded), tuple(feedback), f"recording {path.name}")


__all__ = ["AcceptedPoint", "accepted_points", "choose_run", "recorded_run"]
