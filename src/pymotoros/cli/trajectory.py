"""``pymotoros plan``, ``check``, ``run`` and ``plot``: trajectory files before, during and
after the move.

External contract of ``check`` (docs/trajectories.md)::

    pymotoros check TRAJ [--controller C --robot R | --config CELL.toml] [--from J1,...,Jn] [--json]

exit 0 all clear, 1 MotoROS would refuse a point, 4 accepted with warnings, 2 bad
usage or an unreadable file. ``--json`` prints ``{"accepted", "refusal", "warnings",
"duration_s", "increments"}`` (plus ``start_margin_pulses``); points are numbered as
their sequence numbers (the start point is 0).
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import click

from pymotoros.errors import ConfigError
from pymotoros.models import (
    DEFAULT_CONTROLLER,
    DEFAULT_ROBOT,
    ControllerModel,
    ControllerType,
    RobotModel,
    controller_model,
    robot_model,
)
from pymotoros.models.cell import CellModels, load_cell_models
from pymotoros.trajectory.check import (
    EXIT_OK,
    EXIT_REFUSED,
    EXIT_WARNINGS,
    CheckReport,
    check_trajectory,
)
from pymotoros.trajectory.files import (
    FORMATS,
    Trajectory,
    read_trajectory_file,
    write_trajectory_file,
)

if TYPE_CHECKING:
    from pymotoros.trajectory.plot import RecordedRun

EXIT_USAGE: Final = 2

CHECK_EXIT_HELP: Final = (
    "\b\nExit codes:\n"
    f"  {EXIT_OK}  all clear\n"
    f"  {EXIT_REFUSED}  MotoROS would refuse a point (the message names it and says what to do),\n"
    "     or the motion hits an obstacle of the --config cell or the arm itself\n"
    f"  {EXIT_USAGE}  bad usage or a trajectory file that cannot be read\n"
    f"  {EXIT_WARNINGS}  MotoROS accepts it, but the robot should not do it (warnings)"
)

_TRAJ = click.Path(exists=True, dir_okay=False, path_type=Path)


CONFIG_HELP: Final = (
    "Cell file (the sim's format): check against its controller, groups and FSU "
    "joint-speed limit, instead of --controller/--robot."
)


def model_options(func: Any) -> Any:
    """--controller and --robot (the file's own robot/controller, if it names them,
    is used when the option is not given), or --config CELL.toml instead of both."""
    func = click.option(
        "--config",
        "cell_path",
        type=click.Path(exists=True, dir_okay=False, path_type=Path),
        default=None,
        metavar="CELL.toml",
        help=CONFIG_HELP,
    )(func)
    func = click.option(
        "--robot",
        "robot_name",
        default=None,
        help=f"Robot model [default: the file's, else {DEFAULT_ROBOT}].",
    )(func)
    return click.option(
        "--controller",
        "controller_name",
        type=click.Choice([t.value for t in ControllerType], case_sensitive=False),
        default=None,
        help=f"Controller family [default: the file's, else {DEFAULT_CONTROLLER.value}].",
    )(func)


def reject_models_with_config(cell_path: Path | None, *params: str) -> None:
    """``--config`` names the models: --controller/--robot given with it on the command
    line is a usage error (exit 2), not a silent choice between the two."""
    ctx = click.get_current_context()
    if cell_path is None:
        return
    given = [
        p for p in params if ctx.get_parameter_source(p) is click.core.ParameterSource.COMMANDLINE
    ]
    if given:
        flags = " and ".join("--" + p.removesuffix("_name").replace("_", "-") for p in given)
        raise click.UsageError(
            f"{flags} cannot be combined with --config {cell_path}: the cell file names the "
            "controller and the robot. Give either --config or --controller/--robot."
        )


@dataclass(frozen=True, slots=True)
class Loaded:
    """A trajectory file and the models it is checked against."""

    trajectory: Trajectory
    robot: RobotModel
    controller: ControllerModel
    cell: CellModels | None = None

    @property
    def fsu_pct(self) -> int | None:
        return None if self.cell is None else self.cell.fsu_speed_limit_pct

    def check(self, current: list[float] | None = None) -> CheckReport:
        report = check_trajectory(
            self.trajectory,
            self.robot,
            self.controller,
            current=current,
            fsu_speed_limit_pct=self.fsu_pct,
        )
        if self.cell is not None and self.cell.workspace.obstacles and report.accepted:
            # the cell's obstacles: every contact along the motion (docs/workspace.md);
            # imported here: Pinocchio and Coal load only for a cell with obstacles
            from pymotoros.kinematics.collision import world_for_cell
            from pymotoros.trajectory.collisions import find_collisions

            world = world_for_cell(self.cell)
            report.collisions = find_collisions(self.trajectory, self.cell, report.per_group, world)
        return report

    def render(self, report: CheckReport) -> str:
        return render(report, self.trajectory, self.robot, self.controller, self.cell)


def load(
    path: Path, robot_name: str | None, controller_name: str | None
) -> tuple[Trajectory, RobotModel, ControllerModel]:
    """The file and the models it is checked against; errors are usage errors (exit 2)."""
    loaded = load_models(path, robot_name, controller_name, None)
    return loaded.trajectory, loaded.robot, loaded.controller


def load_models(
    path: Path, robot_name: str | None, controller_name: str | None, cell_path: Path | None
) -> Loaded:
    """:func:`load`, or with a cell file its models (numpy-free models layer, as
    ``pymotoros move --config`` reads it); errors are usage errors (exit 2)."""
    if cell_path is None:
        try:
            robot = robot_model(robot_name or DEFAULT_ROBOT)
            traj = read_trajectory_file(path, robot)
            if robot_name is None and traj.robot is not None:
                robot = robot_model(traj.robot)
            controller = controller_model(controller_name or traj.controller or DEFAULT_CONTROLLER)
            traj.group_columns(robot)  # names every joint of whole groups of this robot
        except ConfigError as exc:
            raise click.BadParameter(str(exc), param_hint="TRAJ") from None
        return Loaded(traj, robot, controller)
    try:
        cell = load_cell_models(cell_path)
    except ConfigError as exc:
        raise click.BadParameter(str(exc), param_hint="--config") from None
    try:
        traj = read_trajectory_file(path, cell.robot)
        traj.group_columns(cell.robot)
    except ConfigError as exc:
        raise click.BadParameter(str(exc), param_hint="TRAJ") from None
    for warning in cell.warnings:
        click.echo(f"warning: {warning}", err=True)
    if traj.robot is not None and traj.robot.lower() not in cell.robots:
        click.echo(
            f"warning: {path.name} was made for {traj.robot}; checking it against the cell "
            f"{cell.name} ({', '.join(cell.robots)})",
            err=True,
        )
    if traj.controller is not None and traj.controller.lower() != cell.controller.type.value:
        click.echo(
            f"warning: {path.name} was made for a {traj.controller}; checking it against the "
            f"cell's {cell.controller.type.value}",
            err=True,
        )
    return Loaded(traj, cell.robot, cell.controller, cell)


def _parse_from(value: str | None, count: int) -> list[float] | None:
    if value is None:
        return None
    parts = [p.strip() for p in value.split(",")]
    if len(parts) != count:
        raise click.BadParameter(
            f"needs {count} comma-separated values (the file's joints, rad), got {len(parts)}",
            param_hint="--from",
        )
    try:
        out = [float(p) for p in parts]
    except ValueError:
        raise click.BadParameter(f"not all numbers: {value!r}", param_hint="--from") from None
    if not all(math.isfinite(v) for v in out):
        raise click.BadParameter("values must be finite", param_hint="--from")
    return out


def render(
    report: CheckReport,
    traj: Trajectory,
    robot: RobotModel,
    controller: ControllerModel,
    cell: CellModels | None = None,
) -> str:
    """The human report of ``pymotoros check``."""
    what = f"{robot.name} on {controller.type.value}"
    if cell is not None:
        what = f"cell {cell.name!r} ({', '.join(cell.robots)} on {controller.type.value}"
        if cell.fsu_speed_limit_pct is not None:
            what += f", FSU joint speeds {cell.fsu_speed_limit_pct} %"
        what += ")"
    lines = [f"{len(traj.times)} points, {len(traj.joint_names)} joints, {what}"]
    r = report.refusal
    if r is not None:
        lines.append(
            f"REFUSED: MotoROS would answer INVALID ({r.result}) subcode {r.subcode} to point "
            f"{r.point}" + (f", {r.axis}" if r.axis else "") + f": {r.meaning}"
        )
        lines.append(f"  value {r.value:.6g}, limit {r.limit:.6g}")
        lines.append(f"  {r.message}")
        lines.append(f"  remedy: {r.remedy}")
        return "\n".join(lines)
    lines.append(
        f"accepted: {report.increments} increments, {report.duration_s:.3f} s "
        f"(planned {traj.duration:.3f} s)"
    )
    if report.start_margin_pulses is not None:
        lines.append(f"start margin: {report.start_margin_pulses} pulses of the 30 MotoROS allows")
    for w in report.warnings:
        lines.append(f"warning [{w.kind}] point {w.point}: {w.text}")
    if not report.warnings:
        lines.append("no warnings")
    lines.extend(c.text() for c in report.collisions)
    return "\n".join(lines)


@click.command(epilog=CHECK_EXIT_HELP, context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("traj", metavar="TRAJ", type=_TRAJ)
@model_options
@click.option(
    "--from",
    "from_",
    metavar="J1,...,Jn",
    help="The robot's current position (rad, the file's joints): checks the start margin.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
def check(
    traj: Path,
    robot_name: str | None,
    controller_name: str | None,
    cell_path: Path | None,
    from_: str | None,
    as_json: bool,
) -> None:
    """Pre-flight a trajectory file (.csv, .json, .yaml) offline.

    Runs MotoROS 1.9.12's validation and interpolation exactly (the twin's engine),
    then checks what MotoROS never does: joint limits between points, per-tick
    increments and accelerations, feed rate, start margin; with --config, also what
    the cell's FSU joint-speed limit does to the motion and every collision with the
    obstacles of its [workspace] (docs/workspace.md).
    """
    reject_models_with_config(cell_path, "robot_name", "controller_name")
    loaded = load_models(traj, robot_name, controller_name, cell_path)
    current = _parse_from(from_, len(loaded.trajectory.joint_names))
    report = loaded.check(current)
    if as_json:
        click.echo(json.dumps(report.to_json()))
    else:
        click.echo(loaded.render(report))
    sys.exit(report.exit_code)


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("waypoints", metavar="WAYPOINTS.csv", type=_TRAJ)
@click.option("--robot", "robot_name", default=DEFAULT_ROBOT, show_default=True)
@click.option(
    "--controller",
    "controller_name",
    type=click.Choice([t.value for t in ControllerType], case_sensitive=False),
    default=DEFAULT_CONTROLLER.value,
    show_default=True,
)
@click.option(
    "--config",
    "cell_path",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    default=None,
    metavar="CELL.toml",
    help="Cell file (the sim's format): plan for its groups and controller, instead of "
    "--controller/--robot.",
)
@click.option(
    "--speed-scale",
    type=click.FloatRange(0, 1, min_open=True),
    default=1.0,
    show_default=True,
    help="Velocity scaling of the model's limits (as MoveIt's).",
)
@click.option(
    "--accel-scale",
    type=click.FloatRange(0, 1, min_open=True),
    default=1.0,
    show_default=True,
    help="Acceleration scaling of the model's limits.",
)
@click.option(
    "--sample",
    "sample_s",
    type=click.FloatRange(0.004, 10),
    default=0.05,
    show_default=True,
    help="Approximate seconds between points.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False, path_type=Path),
    required=True,
    help="Trajectory file to write (.csv, .json, .yaml).",
)
@click.option(
    "--avoid",
    is_flag=True,
    help="Go around the obstacles of the --config cell's [workspace] (OMPL); the result "
    "passes `pymotoros check --config`. A goal that cannot be reached is refused (exit 1).",
)
def plan(
    waypoints: Path,
    robot_name: str,
    controller_name: str,
    cell_path: Path | None,
    speed_scale: float,
    accel_scale: float,
    sample_s: float,
    output: Path,
    avoid: bool,
) -> None:
    """Time waypoints (one row per waypoint, every joint of the robot, rad; an optional
    header row) within the robot's limits, and write the trajectory."""
    from pymotoros.trajectory.planning import plan_waypoints

    reject_models_with_config(cell_path, "robot_name", "controller_name")
    try:
        if cell_path is None:
            robot = robot_model(robot_name)
            controller = controller_model(controller_name)
        else:
            cell = load_cell_models(cell_path)
            robot, controller = cell.robot, cell.controller
            pct = cell.fsu_speed_limit_pct
            if pct is not None and speed_scale * 100 > pct:
                click.echo(
                    f"warning: the cell's FSU limits joint speeds to {pct} %: at "
                    f"--speed-scale {speed_scale:g} the robot will run behind the plan "
                    f"(`pymotoros check --config` says by how much); plan with "
                    f"--speed-scale {pct / 100:g} or less",
                    err=True,
                )
        rows = []
        for number, line in enumerate(waypoints.read_text(encoding="utf-8").splitlines(), 1):
            if not line.strip():
                continue
            try:
                rows.append([float(c) for c in line.split(",")])
            except ValueError:
                if number == 1:
                    continue  # header
                raise ConfigError(f"{waypoints.name} line {number}: not all numbers") from None
        if avoid:  # around the cell's obstacles (trajectory/avoid.py)
            result = _plan_avoiding(rows, cell_path, speed_scale, accel_scale, sample_s)
        else:
            result = plan_waypoints(
                rows,
                robot,
                controller,
                velocity_scaling=speed_scale,
                acceleration_scaling=accel_scale,
                sample_s=sample_s,
            )
        write_trajectory_file(result, output)
    except ConfigError as exc:
        raise click.BadParameter(str(exc)) from None
    click.echo(
        f"wrote {output}: {len(result.times)} points, {result.duration:.3f} s "
        f"(formats: {', '.join(FORMATS)})"
    )


def _plan_avoiding(
    rows: list[list[float]],
    cell_path: Path | None,
    speed_scale: float,
    accel_scale: float,
    sample_s: float,
) -> Trajectory:
    """``plan --avoid``: the cell's obstacles are needed; a blocked goal is one line, exit 1."""
    from pymotoros.kinematics.collision import world_for_cell
    from pymotoros.trajectory.avoid import PathBlockedError, plan_avoiding

    if cell_path is None:
        raise click.UsageError("--avoid needs --config CELL.toml: the cell names the obstacles")
    cell = load_cell_models(cell_path)
    try:
        return plan_avoiding(
            rows,
            cell,
            world_for_cell(cell),
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
            sample_s=sample_s,
        )
    except PathBlockedError as exc:
        click.echo(f"refused: {exc}", err=True)
        sys.exit(EXIT_REFUSED)


# --------------------------------------------------------------------------- run


def client_trajectory(traj: Trajectory, robot: RobotModel) -> tuple[Any, tuple[int, ...]]:
    """(the client's JointTrajectory, its groups): exactly the file's points, its joints
    reordered group by group as the client sends them (no re-timing)."""
    from pymotoros.client.planning import JointTrajectory, TrajectoryPoint

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


def _robot_options(func: Any) -> Any:
    from pymotoros.cli.robot import robot_options

    return robot_options(func)


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("traj", metavar="TRAJ", type=_TRAJ)
@_robot_options
@click.option("--force", is_flag=True, help="Send even if `pymotoros check` finds a problem.")
@click.option("--enable", "enable_first", is_flag=True, help="Enter trajectory mode first.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def run(traj: Path, force: bool, enable_first: bool, as_json: bool, **kwargs: Any) -> None:
    """Stream exactly the points of a trajectory file to the robot (no re-timing).

    The robot must be enabled as for `move` (or give --enable) and stand at the first
    point. The file is checked first (as `pymotoros check`); a refusal or a warning
    stops the command before anything moves, unless --force.
    """
    import asyncio
    import contextlib

    from pymotoros.cli.robot import _move_data, _target, connected, progress_bar
    from pymotoros.cli.robot import run as run_client
    from pymotoros.client.streaming import MoveResult
    from pymotoros.errors import PymotorosError

    reject_models_with_config(kwargs.get("cell_path"), "robot", "controller")
    target = _target(kwargs)
    loaded = load_models(
        traj,
        None if target.cell is not None else target.robot,
        None if target.cell is not None else target.controller,
        target.cell,
    )
    trajectory, robot = loaded.trajectory, loaded.robot
    report = loaded.check()
    if report.exit_code != EXIT_OK and not force:
        click.echo(loaded.render(report), err=True)
        click.echo("not started: fix the trajectory or give --force", err=True)
        sys.exit(report.exit_code)
    joint, groups = client_trajectory(trajectory, robot)

    async def work() -> MoveResult:
        async with connected(target, motion=True, state=True, io=False) as client:
            if enable_first:
                await client.start_trajectory_mode()
            with progress_bar("running") as progress:
                try:
                    result = await client.execute(
                        joint, groups=groups, on_progress=progress, check_speed=not force
                    )
                except asyncio.CancelledError:
                    with contextlib.suppress(PymotorosError):
                        await asyncio.shield(client.stop_motion())
                    raise
            return result

    result = run_client(target, work, stoppable=True)  # Ctrl-C / SIGTERM: STOP_MOTION
    if as_json:
        click.echo(json.dumps(_move_data(result)))
    else:
        pos = ", ".join(f"{p:.4f}" for p in result.final_positions)
        click.echo(
            f"reached [{pos}] in {result.elapsed_s:.2f} s (file {trajectory.duration:.2f} s, "
            f"MotoROS {report.duration_s:.3f} s predicted, {result.stream.points} points)"
        )


# --------------------------------------------------------------------------- plot


def recorded_run(path: Path, traj: Trajectory, robot: RobotModel) -> RecordedRun:
    """The run of ``traj`` in a session recording (``--record``, ``sim --record``, or a
    Wireshark capture): the points the controller accepted and the feedback it sent.

    The points are paired with their MOTO_MOTION_REPLY (MotoROS answers in order);
    BUSY answers make the client resend, so only the SUCCESS one counts. Time 0 is
    that reply to the start point (sequence 0). A recording may hold several
    trajectories: the one with the file's number of points is used (the last such),
    else the last one, with a warning. Errors are usage errors (exit 2).
    """
    import numpy as np

    from pymotoros.client.recording import Direction, RecordingError, read_recording
    from pymotoros.protocol.constants import MsgType, Port, ResultCode
    from pymotoros.protocol.messages import (
        JointFeedback,
        JointTrajPtFull,
        MotoJointFeedbackEx,
        MotoJointTrajPtFullEx,
        MotoMotionReply,
    )
    from pymotoros.trajectory.plot import RecordedRun, Series

    try:
        rec = read_recording(path)
    except (RecordingError, OSError) as exc:
        raise click.BadParameter(str(exc), param_hint="--recording") from None
    point_types = {int(MsgType.JOINT_TRAJ_PT_FULL), int(MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX)}
    # accepted points, in order: (reply time, sequence, [(group, time, pos, vel)])
    accepted: list[tuple[float, int, list[tuple[int, float, tuple[float, ...], tuple[float, ...]]]]]
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
                    accepted.append((m.offset, request.sequence, records))
                elif isinstance(request, MotoJointTrajPtFullEx):
                    records = [(g.group_no, g.time, g.pos, g.vel) for g in request.groups]
                    accepted.append((m.offset, request.sequence, records))
    runs: list[list[Any]] = []
    for item in accepted:
        if item[1] == 0 or not runs:
            runs.append([])
        runs[-1].append(item)
    if not runs:
        raise click.BadParameter(
            f"{path} holds no trajectory point the controller accepted "
            "(record a `pymotoros run` with --record)",
            param_hint="--recording",
        )
    matching = [r for r in runs if len(r) == len(traj.times)]
    chosen = matching[-1] if matching else runs[-1]
    if not matching:
        click.echo(
            f"warning: {path.name}: no trajectory of {len(traj.times)} points (the file's); "
            f"plotting the last one recorded ({len(chosen)} points)",
            err=True,
        )
    t0 = chosen[0][0]
    columns = dict(traj.group_columns(robot))
    commanded: list[Series] = []
    for gi, cols in columns.items():
        n = len(cols)
        rows = [(t, p[:n], v[:n]) for _, _, recs in chosen for g, t, p, v in recs if g == gi]
        if not rows:
            continue
        times = np.array([r[0] for r in rows], dtype=np.float64)
        commanded.append(
            Series(
                times - times[0],
                np.array([r[1] for r in rows], dtype=np.float64),
                tuple(cols),
                np.array([r[2] for r in rows], dtype=np.float64),
            )
        )
    single: dict[int, list[tuple[float, tuple[float, ...]]]] = {}
    multi: dict[int, list[tuple[float, tuple[float, ...]]]] = {}
    for conn in rec.on(Port.STATE):
        for m in conn.messages:
            msg = m.message
            if isinstance(msg, JointFeedback):
                single.setdefault(msg.group_no, []).append((m.offset - t0, msg.pos))
            elif isinstance(msg, MotoJointFeedbackEx):
                for g in msg.groups:
                    multi.setdefault(g.group_no, []).append((m.offset - t0, g.pos))
    feedback: list[Series] = []
    for gi, cols in columns.items():
        samples = single.get(gi) or multi.get(gi)  # MotoROS sends both for ≥ 2 groups
        if not samples:
            continue
        n = len(cols)
        feedback.append(
            Series(
                np.array([s[0] for s in samples], dtype=np.float64),
                np.array([s[1][:n] for s in samples], dtype=np.float64),
                tuple(cols),
            )
        )
    if not feedback:
        click.echo(f"warning: {path.name}: no feedback of the file's groups recorded", err=True)
    return RecordedRun(tuple(commanded), tuple(feedback), f"recording {path.name}")


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("traj", metavar="TRAJ", type=_TRAJ)
@model_options
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False, path_type=Path),
    required=True,
    help="PNG file to write.",
)
@click.option(
    "--recording",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    default=None,
    metavar="REC.pcapng",
    help="A session recording of a run of this trajectory (--record): adds the commanded "
    "and feedback positions, the lag and the tracking error.",
)
def plot(
    traj: Path,
    robot_name: str | None,
    controller_name: str | None,
    cell_path: Path | None,
    output: Path,
    recording: Path | None,
) -> None:
    """Plot a trajectory per joint: planned and MotoROS-interpolated positions and
    velocities, with the limits; with --recording, also what the robot was sent and
    reported, its lag and its tracking error. A trajectory MotoROS would refuse is not
    plotted (exit 1, as `pymotoros check`)."""
    from pymotoros.trajectory.plot import plot_trajectory, tracking

    reject_models_with_config(cell_path, "robot_name", "controller_name")
    loaded = load_models(traj, robot_name, controller_name, cell_path)
    report = loaded.check()
    if not report.accepted:
        click.echo(loaded.render(report), err=True)
        sys.exit(EXIT_REFUSED)
    run = None if recording is None else recorded_run(recording, loaded.trajectory, loaded.robot)
    plot_trajectory(loaded.trajectory, loaded.robot, loaded.controller, report, output, run=run)
    click.echo(f"wrote {output}")
    if run is not None:
        for j, name in enumerate(loaded.trajectory.joint_names):
            track = tracking(run, j)
            if track is None or track.lag_ms is None:
                continue
            click.echo(
                f"  {name}: feedback lag {track.lag_ms:.0f} ms, tracking error mean "
                f"{track.mean_error:.3g}, max {track.max_error:.3g}"
            )
