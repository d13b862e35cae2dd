"""``pymotoros plan``, ``check`` and ``plot``: trajectory files before and after the move
(``run``, which streams one to the robot, is ``cli/trajectory_run.py``).

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
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, TypeVar

import click

from pymotoros.cli.options import (
    EXIT_USAGE,
    BadInput,
    InputFile,
    config_option,
    controller_option,
    json_option,
    model_options,
    number_list,
    output_option,
    robot_option,
    scale_options,
)
from pymotoros.cli.recorded_run import recorded_run
from pymotoros.errors import ConfigError
from pymotoros.models import (
    DEFAULT_CONTROLLER,
    DEFAULT_ROBOT,
    ControllerModel,
    RobotModel,
    controller_model,
    robot_model,
)
from pymotoros.models.cell import CellModels, load_cell_models
from pymotoros.protocol.constants import MAX_TOOL_NUMBER, InvalidSubcode
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

_F = TypeVar("_F", bound=Callable[..., Any])

CHECK_EXIT_HELP: Final = (
    "\b\nExit codes:\n"
    f"  {EXIT_OK}  all clear\n"
    f"  {EXIT_REFUSED}  MotoROS would refuse a point (the message names it and says what to do),\n"
    "     or the motion hits an obstacle of the --config cell or the arm itself\n"
    f"  {EXIT_USAGE}  bad usage or a trajectory file that cannot be read\n"
    f"  {EXIT_WARNINGS}  MotoROS accepts it, but the robot should not do it (warnings)"
)

TRAJ_FILE = InputFile("trajectory file (.csv, .json, .yaml)")
"""The TRAJ argument of plan, check, run and plot."""


def collision_tool_option(func: _F) -> _F:
    """``--tool N``: the tool whose shape the collision check puts on the flange."""
    return click.option(
        "--tool",
        "tool",
        type=click.IntRange(0, MAX_TOOL_NUMBER),
        default=None,
        metavar="N",
        help="With a --config cell that has obstacles: the tool on the flange (its "
        "`shape`, else a capsule to its TCP, from the cell's tool data). Default: the "
        "cell's [initial.tool], else tool 0, as the twin boots.",
    )(func)


_MODELS = model_options(controller="controller_name", robot="robot_name")


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
    tool: int | None = None
    """The tool on the flange for the collision check (None: the cell's default)."""

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

            world = world_for_cell(self.cell, [self.tool] * len(self.cell.robot.groups))
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
    path: Path,
    robot_name: str | None,
    controller_name: str | None,
    cell_path: Path | CellModels | None,
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
            raise BadInput(f"TRAJ: {exc}") from None
        return Loaded(traj, robot, controller)
    try:
        cell = cell_path if isinstance(cell_path, CellModels) else load_cell_models(cell_path)
    except ConfigError as exc:
        raise BadInput(f"--config: {exc}") from None
    try:
        traj = read_trajectory_file(path, cell.robot)
        traj.group_columns(cell.robot)
    except ConfigError as exc:
        raise BadInput(f"TRAJ: {exc}") from None
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


def _refusal_unit(subcode: int, axis: str | None, robot: RobotModel) -> str:
    """`` unit`` of a refusal's value and limit (:class:`pymotoros.models.rules.Refusal`):
    pulses for a start-position deviation (3011), the axis's speed unit for 3013, s for a
    point time (3016)."""
    if subcode == InvalidSubcode.DATA_START_POS:
        return " pulses"
    if subcode == InvalidSubcode.DATA_SPEED:
        linear = any(a.linear for g in robot.groups for a in g.axes if a.name == axis)
        return " m/s" if linear else " rad/s"
    if subcode == InvalidSubcode.DATA_TIME:
        return " s"
    return ""


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
        unit = _refusal_unit(r.subcode, r.axis, robot)
        lines.append(f"  value {r.value:.6g}{unit}, limit {r.limit:.6g}{unit}")
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
@click.argument("traj", metavar="TRAJ", type=TRAJ_FILE)
@_MODELS
@click.option(
    "--from",
    "from_",
    metavar="J1,...,Jn",
    help="The robot's current position (rad, the file's joints): checks the start margin.",
)
@json_option("the report")
@collision_tool_option
def check(
    traj: Path,
    robot_name: str | None,
    controller_name: str | None,
    cell_path: Path | None,
    from_: str | None,
    as_json: bool,
    tool: int | None = None,
) -> None:
    """Pre-flight a trajectory file (.csv, .json, .yaml) offline.

    Runs MotoROS 1.9.12's validation and interpolation exactly (the twin's engine),
    then checks what MotoROS never does: joint limits between points, per-tick
    increments and accelerations, feed rate, start margin; with --config, also what
    the cell's FSU joint-speed limit does to the motion and every collision with the
    obstacles of its [workspace] (docs/workspace.md).
    """
    reject_models_with_config(cell_path, "robot_name", "controller_name")
    loaded = replace(load_models(traj, robot_name, controller_name, cell_path), tool=tool)
    current = number_list(
        from_, len(loaded.trajectory.joint_names), hint="--from", what="the file's joints, rad"
    )
    report = loaded.check(current)
    if as_json:
        click.echo(json.dumps(report.to_json()))
    else:
        click.echo(loaded.render(report))
    sys.exit(report.exit_code)


def read_waypoints(path: Path, count: int) -> list[list[float]]:
    """The rows of a waypoints CSV (an optional header row), each of ``count`` finite
    numbers; errors name the line and say what it needs (exit 2, one line)."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path.name}: cannot read it as UTF-8 text ({exc})") from None
    rows = []
    for number, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            row = [float(c) for c in line.split(",")]
        except ValueError:
            if number == 1:
                continue  # header
            raise ConfigError(f"{path.name} line {number}: not all numbers") from None
        if len(row) != count:
            raise ConfigError(
                f"{path.name} line {number}: {len(row)} values, the robot has {count} joints; "
                "give one value per joint (rad)"
            )
        if not all(math.isfinite(v) for v in row):
            raise ConfigError(
                f"{path.name} line {number}: {line.strip()!r} holds a value that is not a "
                "finite number; give every joint in rad"
            )
        rows.append(row)
    return rows


def _plan_models(
    robot_name: str, controller_name: str, cell_path: Path | None, speed_scale: float
) -> tuple[RobotModel, ControllerModel]:
    """The models to plan for; with a cell, a warning when its FSU limit is below the
    speed scaling (the robot would run behind the plan)."""
    if cell_path is None:
        return robot_model(robot_name), controller_model(controller_name)
    cell = load_cell_models(cell_path)
    pct = cell.fsu_speed_limit_pct
    if pct is not None and speed_scale * 100 > pct:
        click.echo(
            f"warning: the cell's FSU limits joint speeds to {pct} %: at "
            f"--speed-scale {speed_scale:g} the robot will run behind the plan "
            f"(`pymotoros check --config` says by how much); plan with "
            f"--speed-scale {pct / 100:g} or less",
            err=True,
        )
    return cell.robot, cell.controller


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("waypoints", metavar="WAYPOINTS.csv", type=InputFile("waypoints CSV"))
@robot_option("robot_name")
@controller_option("controller_name")
@config_option()
@scale_options
@click.option(
    "--sample",
    "sample_s",
    type=click.FloatRange(0.004, 10),
    default=0.05,
    show_default=True,
    help="Approximate seconds between points.",
)
@output_option("Trajectory file to write (.csv, .json, .yaml)", required=True)
@click.option(
    "--avoid",
    is_flag=True,
    help="Go around the obstacles of the --config cell's [workspace] (OMPL); the result "
    "passes `pymotoros check --config`. A goal that cannot be reached is refused (exit 1).",
)
@collision_tool_option
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
    tool: int | None = None,
) -> None:
    """Time waypoints (one row per waypoint, every joint of the robot, rad; an optional
    header row) within the robot's limits, and write the trajectory."""
    from pymotoros.trajectory.planning import plan_waypoints

    reject_models_with_config(cell_path, "robot_name", "controller_name")
    try:
        robot, controller = _plan_models(robot_name, controller_name, cell_path, speed_scale)
        rows = read_waypoints(waypoints, sum(g.num_axes for g in robot.groups))
        if avoid:  # around the cell's obstacles (trajectory/avoid.py)
            result = _plan_avoiding(rows, cell_path, speed_scale, accel_scale, sample_s, tool)
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
        raise BadInput(str(exc)) from None
    except OSError as exc:
        raise BadInput(f"cannot write {output}: {exc.strerror}") from None
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
    tool: int | None = None,
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
            world_for_cell(cell, [tool] * len(cell.robot.groups)),
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
            sample_s=sample_s,
        )
    except PathBlockedError as exc:
        click.echo(f"refused: {exc}", err=True)
        sys.exit(EXIT_REFUSED)


# --------------------------------------------------------------------------- plot


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("traj", metavar="TRAJ", type=TRAJ_FILE)
@_MODELS
@output_option("PNG file to write", required=True)
@click.option(
    "--recording",
    type=InputFile("session recording (pcapng)"),
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
    from pymotoros.trajectory.plot import plot_trajectory

    reject_models_with_config(cell_path, "robot_name", "controller_name")
    _check_image_suffix(output)
    loaded = load_models(traj, robot_name, controller_name, cell_path)
    report = loaded.check()
    if not report.accepted:
        click.echo(loaded.render(report), err=True)
        sys.exit(EXIT_REFUSED)
    run = None if recording is None else recorded_run(recording, loaded.trajectory, loaded.robot)
    try:
        plot_trajectory(loaded.trajectory, loaded.robot, loaded.controller, report, output, run=run)
    except OSError as exc:
        raise BadInput(f"cannot write {output}: {exc.strerror}") from None
    click.echo(f"wrote {output}")
    if run is not None:
        _print_tracking(run, loaded.trajectory, loaded.robot)


def _check_image_suffix(output: Path) -> None:
    """An image format matplotlib writes (.png, .svg, .pdf …), told before the work."""
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    if output.suffix.lower().lstrip(".") not in formats:
        raise BadInput(
            f"-o {output}: cannot tell an image format from {output.suffix or 'no suffix'!r}; "
            f"end the name in .{', .'.join(sorted(formats))}"
        )


def _print_tracking(run: RecordedRun, traj: Trajectory, robot: RobotModel) -> None:
    """Per joint: the feedback lag and the tracking error, in the joint's unit (rad, or
    m for a linear axis)."""
    from pymotoros.trajectory.plot import tracking

    linear = {a.name: a.linear for g in robot.groups for a in g.axes}
    for j, name in enumerate(traj.joint_names):
        track = tracking(run, j)
        if track is None or track.lag_ms is None:
            continue
        unit = "m" if linear.get(name) else "rad"
        click.echo(
            f"  {name}: feedback lag {track.lag_ms:.0f} ms, tracking error mean "
            f"{track.mean_error:.3g} {unit}, max {track.max_error:.3g} {unit}"
        )
