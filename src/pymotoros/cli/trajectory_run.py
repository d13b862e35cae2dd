"""``pymotoros run``: stream exactly the points of a trajectory file to the robot.

The file is checked first as ``pymotoros check`` does (``cli/trajectory.py``), its first
point against where the robot rests (MotoROS's 30-pulse start tolerance) before anything
is sent; then the points go out unchanged, with a progress line, and Ctrl-C or SIGTERM
stops the robot (STOP_MOTION) first.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import sys
from pathlib import Path
from typing import Any

import click

from pymotoros.cli.move_report import move_data, progress_bar
from pymotoros.cli.options import enable_option, json_option, robot_options
from pymotoros.cli.session import connected, target_from_options
from pymotoros.cli.session import run as run_client
from pymotoros.cli.trajectory import TRAJ_FILE, load_models, reject_models_with_config
from pymotoros.client import RobotClient
from pymotoros.client.errors import reply_error
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.preflight import start_deviations
from pymotoros.client.streaming import MoveResult, deviation_text, joint_values_text
from pymotoros.errors import PymotorosError
from pymotoros.models import RobotModel
from pymotoros.protocol.constants import InvalidSubcode, MsgType, ResultCode
from pymotoros.trajectory.check import EXIT_OK
from pymotoros.trajectory.files import Trajectory

__all__ = ["check_start", "client_trajectory", "run"]


def client_trajectory(
    traj: Trajectory, robot: RobotModel
) -> tuple[JointTrajectory, tuple[int, ...]]:
    """(the client's JointTrajectory, its groups): exactly the file's points, its joints
    reordered group by group as the client sends them (no re-timing)."""
    columns = traj.group_columns(robot)
    groups = tuple(g for g, _ in columns)
    order = [c for _, cols in columns for c in cols]
    points = tuple(
        TrajectoryPoint(
            float(t), tuple(float(x) for x in p[order]), tuple(float(x) for x in v[order])
        )
        for t, p, v in zip(traj.times, traj.positions, traj.velocities, strict=True)
    )
    return JointTrajectory(points, float(traj.times[-1])), groups


async def check_start(client: RobotClient, joint: JointTrajectory, groups: tuple[int, ...]) -> None:
    """Point 0 against where the robot rests, before anything is sent: MotoROS would
    refuse it with 3011 beyond 30 pulses; this says so with the numbers of every joint
    beyond it, in the words of the refusal itself (as ``move`` reports a 3011)."""
    models = [client.robot.groups[g] for g in groups]
    here = await client.current_positions(groups)  # settled: what MotoROS compares with
    devs = start_deviations(joint.points[0], models, here, client.controller)
    if devs:
        kind = (
            MsgType.JOINT_TRAJ_PT_FULL if len(groups) == 1 else MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX
        )
        raise reply_error(
            ResultCode.INVALID,
            InvalidSubcode.DATA_START_POS,
            int(kind),
            point=0,
            detail=deviation_text(devs, "start") + "; checked before sending",
            deviations=devs,
        )


async def _stream_file(
    client: RobotClient,
    joint: JointTrajectory,
    groups: tuple[int, ...],
    *,
    enable_first: bool,
    force: bool,
) -> MoveResult:
    """Enable if asked, check the start, stream the points with a progress line; on
    Ctrl-C or SIGTERM STOP_MOTION first."""
    await client.wait_for_state()
    if enable_first:
        await client.start_trajectory_mode()
    await check_start(client, joint, groups)
    try:
        with progress_bar("running", client, groups, duration_s=joint.duration) as progress:
            # checked above as `check` does, obstacles included: the client's guard
            # would only repeat it (and must not refuse what --force sends)
            return await client.execute(
                joint, groups=groups, on_progress=progress, check_speed=not force, force=True
            )
    except asyncio.CancelledError as exc:
        stop = client.streamer.last_stop  # the library's own stop of this run, if any
        if stop is None or not stop.stopped:  # none, or it failed: STOP_MOTION here
            with contextlib.suppress(PymotorosError):
                await asyncio.shield(client.stop_motion())
        for note in getattr(exc, "__notes__", ()):  # the client's stop: where it stands
            click.echo(note, err=True)
        raise


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("traj", metavar="TRAJ", type=TRAJ_FILE)
@robot_options
@click.option("--force", is_flag=True, help="Send even if `pymotoros check` finds a problem.")
@enable_option
@json_option()
def run(traj: Path, force: bool, enable_first: bool, as_json: bool, **kwargs: Any) -> None:
    """Stream exactly the points of a trajectory file to the robot (no re-timing).

    The robot must be enabled as for `move` (or give --enable) and stand at the first
    point: the first point is compared with the robot's settled feedback before
    anything is sent (MotoROS's 30-pulse start tolerance, the numbers per joint). The
    file is checked first (as `pymotoros check`); a refusal or a warning stops the
    command before anything moves, unless --force.
    """
    reject_models_with_config(kwargs.get("cell_path"), "robot", "controller")
    target = target_from_options(kwargs)
    loaded = load_models(
        traj,
        None if target.cell is not None else target.robot,
        None if target.cell is not None else target.controller,
        target.cell,
    )
    report = loaded.check()
    if report.exit_code != EXIT_OK and not force:
        click.echo(loaded.render(report), err=True)
        click.echo("not started: fix the trajectory or give --force", err=True)
        sys.exit(report.exit_code)
    joint, groups = client_trajectory(loaded.trajectory, loaded.robot)

    async def work() -> MoveResult:
        async with connected(target, motion=True, state=True, io=False) as client:
            return await _stream_file(client, joint, groups, enable_first=enable_first, force=force)

    result = run_client(target, work, stoppable=True)  # Ctrl-C / SIGTERM: STOP_MOTION
    if as_json:
        click.echo(json.dumps(move_data(result)))
    else:
        models = [loaded.robot.groups[g] for g in result.groups]
        pos = joint_values_text(result.final_positions, models)
        click.echo(
            f"reached {pos} in {result.elapsed_s:.2f} s (file "
            f"{loaded.trajectory.duration:.2f} s, MotoROS {report.duration_s:.3f} s "
            f"predicted, {result.stream.points} points)"
        )
