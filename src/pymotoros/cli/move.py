"""``pymotoros move``: to joint positions, a named pose, a TCP pose or by a relative step.

The goal is checked against the robot model before anything is sent; the move is
planned from where the robot rests, watched with a progress line, and a refused or
stopped move says where the robot came to rest and how far it is from the goal.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Sequence
from typing import Any, Final

import click

from pymotoros.cli.cartesian import cartesian_move, tool_option, use_tool
from pymotoros.cli.move_goal import MoveGoal, MoveRequest, need_obstacles, resolve_goal
from pymotoros.cli.move_report import move_data, progress_bar, to_user, unit_of
from pymotoros.cli.options import (
    InputFile,
    NumbersCommand,
    deg_option,
    enable_option,
    group_option,
    json_option,
    robot_options,
    scale_options,
)
from pymotoros.cli.session import (
    EXIT_CODES_HELP,
    connected,
    echo_json,
    fail,
    run,
    target_from_options,
)
from pymotoros.client import ReplyError, RobotClient
from pymotoros.client.planning import JointTrajectory
from pymotoros.client.streaming import FollowingSample, MoveResult, joint_values_text
from pymotoros.errors import PathBlockedError, PymotorosError
from pymotoros.models import GroupModel

__all__ = ["MoveBlockedError", "move"]


class MoveBlockedError(PymotorosError):
    """The planned move hits an obstacle of the cell (or the arm itself): exit code 1,
    nothing sent."""


SETTLE_TIMEOUT_S: Final = 3.0
"""How long a refused or stopped move waits for the robot to come to rest before it says
where the robot stands (an E-stop's braking takes well under a second)."""


async def _cartesian(
    client: RobotClient,
    req: MoveRequest,
    goal: MoveGoal,
    progress: Callable[[FollowingSample], None],
) -> MoveResult:
    return await cartesian_move(
        client,
        pose=goal.pose,
        relative=goal.relative,
        linear=req.linear or goal.relative is not None,
        frame="tool" if req.frame == "tool" else "base",
        tcp_speed_mm_s=req.tcp_speed_mm_s,
        group=goal.groups[0],
        speed_scale=req.speed_scale,
        accel_scale=req.accel_scale,
        on_progress=progress,
        tool=req.tool,
        avoid=req.avoid,
        force=req.force,
    )


async def _joint_plan(client: RobotClient, req: MoveRequest, goal: MoveGoal) -> JointTrajectory:
    """The joint move from where the robot rests (planned before the progress line
    starts, so that it can tell the time left from the plan); with --avoid around the
    cell's obstacles (a goal that cannot be reached: exit 1, nothing sent)."""
    start = await client.current_positions(goal.groups)
    try:
        return client.plan(
            start,
            goal.goal,
            groups=goal.groups,
            speed_scale=req.speed_scale,
            accel_scale=req.accel_scale,
            avoid=req.avoid,
        )
    except PathBlockedError as exc:
        raise MoveBlockedError(f"not started: {exc}") from None


async def _settled_where(
    client: RobotClient, goal: MoveGoal, deg: bool, what: str, timeout_s: float
) -> str:
    """:func:`_where` once the robot has come to rest (an E-stop brakes for a moment:
    read at once, the position would be several mrad short of where it stops)."""
    with contextlib.suppress(PymotorosError, TimeoutError):
        await client.current_positions(goal.groups, timeout_s=min(timeout_s, SETTLE_TIMEOUT_S))
    return _where(client, goal.groups, goal.models, goal.goal, deg, what)


async def _move_watched(
    client: RobotClient,
    req: MoveRequest,
    goal: MoveGoal,
    timeout_s: float,
) -> MoveResult:
    """The move with its progress line; on Ctrl-C/SIGTERM STOP_MOTION, and a refusal
    mid-move says where the robot came to rest."""
    try:
        planned = None if req.cartesian else await _joint_plan(client, req, goal)
        if planned is not None and not req.force:  # before the progress line starts
            client.guard(planned, goal.groups)
        duration = None if planned is None else planned.duration
        with progress_bar("moving", client, goal.groups, duration_s=duration, deg=req.deg) as bar:
            if planned is None:
                return await _cartesian(client, req, goal, bar)
            # checked just above: the client's guard runs once
            return await client.execute(planned, groups=goal.groups, on_progress=bar, force=True)
    except PathBlockedError as exc:  # the client's guard, or --avoid finding no way
        raise MoveBlockedError(f"not started: {exc}") from None
    except asyncio.CancelledError:
        stop = client.streamer.last_stop  # the library's own stop of this move, if any
        if stop is None or not stop.stopped:  # none (e.g. still planning), or it failed
            with contextlib.suppress(PymotorosError):
                await asyncio.shield(client.stop_motion())
        if stop is not None and stop.at_rest:  # it waited for rest already
            where = _where(
                client, goal.groups, goal.models, goal.goal, req.deg, "stopped (STOP_MOTION)"
            )
        else:
            where = await asyncio.shield(
                _settled_where(client, goal, req.deg, "stopped (STOP_MOTION)", timeout_s)
            )
        click.echo(where, err=True)  # the progress line has ended its line already
        raise
    except ReplyError as exc:
        stop = exc.early_stop
        if stop is not None:  # the library stopped it and said where: add only the distance
            if stop.at_rest:
                left = _short_of_goal(client, stop.positions, goal, req.deg)
                exc.args = (f"{exc}{left}", *exc.args[1:])
        elif exc.point is not None:  # refused mid-move: say where the robot is
            where = await _settled_where(client, goal, req.deg, "the robot stands", timeout_s)
            exc.args = (f"{exc}; {where}", *exc.args[1:])
        raise


def _say_groups(client: RobotClient, req: MoveRequest, goal: MoveGoal) -> None:
    """A named pose on a robot of several groups: say which groups move (stderr)."""
    if req.name is None or len(client.robot.groups) < 2:
        return
    names = ", ".join(client.robot.groups[g].name for g in goal.groups)
    chosen = "as given with --group" if req.group else "every group the pose sets; --group chooses"
    click.echo(f"{req.name}: moving {names} ({chosen})", err=True)


def _report_move(result: MoveResult, req: MoveRequest, goal: MoveGoal, robot: Any) -> None:
    if req.as_json:
        names = [robot.groups[g].name for g in goal.groups]
        echo_json(move_data(result) | {"groups": names})
        return
    pos = ", ".join(f"{to_user(p, req.deg):.4f}" for p in result.final_positions)
    click.echo(
        f"reached [{pos}] {'deg' if req.deg else 'rad'} in {result.elapsed_s:.2f} s "
        f"(planned {result.trajectory.duration:.2f} s, {result.stream.points} points)"
    )
    following = result.following
    if following.slowed or following.late:
        cause = (
            "a safety speed limit, an override or HOLD slowed it"
            if following.slowed
            else "the controller or the network was late; the robot was not slowed"
        )
        click.echo(  # a note, on stderr as every note: stdout is the result
            f"note: the robot ran up to {following.max_lag_s:.2f} s behind the plan ({cause})",
            err=True,
        )


@click.command(epilog=EXIT_CODES_HELP, cls=NumbersCommand)
@robot_options
@click.argument("joints", nargs=-1, type=float, metavar="[J1 ... Jn]")
@click.option("--named", "name", default=None, help="Move to a named pose instead (e.g. home).")
@click.option(
    "--srdf",
    type=InputFile("SRDF file"),
    default=None,
    help="SRDF file whose group_state entries are the named poses.",
)
@deg_option("J1 ... Jn, results and limit errors")
@scale_options
@group_option(multiple=True)
@enable_option
@json_option()
@click.option(
    "--pose",
    "as_pose",
    is_flag=True,
    help="The values are a TCP pose X Y Z (m) RX RY RZ (rad; deg with --deg) in base "
    "coordinates (base_link raised by the S-axis height, as status prints it), "
    "R = Rz·Ry·Rx; a joint move unless --linear.",
)
@click.option("--linear", is_flag=True, help="With --pose: move the TCP in a straight line.")
@click.option(
    "--relative",
    multiple=True,
    metavar="KEY=VALUE",
    help="Move the TCP by dx, dy, dz (m) / drx, dry, drz (rad; deg with --deg) in a "
    "straight line, e.g. --relative dz=-0.05 (repeatable).",
)
@click.option(
    "--frame",
    type=click.Choice(["base", "tool"]),
    default="base",
    show_default=True,
    help="Frame of --relative: base coordinates or the tool's own axes.",
)
@click.option(
    "--tcp-speed",
    "tcp_speed_mm_s",
    type=click.FloatRange(0.0, min_open=True),
    default=250.0,
    show_default=True,
    help="Maximum TCP speed of a straight-line move, mm/s.",
)
@tool_option
@click.option(
    "--force",
    is_flag=True,
    help="Move even if the --config cell's obstacles are in the planned move's way "
    "(every move, joint or Cartesian, is checked at the controller's 4 ms ticks with the "
    "--tool's shape; a move that backs out of a contact is allowed without it).",
)
@click.option(
    "--avoid",
    is_flag=True,
    help="Plan the joint move (J1 ... Jn, --named, or --pose without --linear) around the "
    "obstacles of the --config cell's [workspace] (OMPL, as `pymotoros plan --avoid`), "
    "with the --tool's shape on the flange; a robot touching an obstacle backs out of it "
    "first. A goal that cannot be reached is refused before anything moves (exit 1).",
)
def move(**kwargs: Any) -> None:
    """Move to joint positions J1 ... Jn (rad, or deg with --deg) or to a named pose.

    Starts from where the robot rests, plans a synchronised, jerk-limited move within
    the robot model's limits and waits until the robot has settled at the goal. With
    several --group options the values are the groups' joints one group after the
    other, sent as one JOINT_TRAJ_PT_FULL_EX trajectory. --named moves every group the
    pose sets (all groups for home) unless --group names some, and says which.
    With a --config cell that has obstacles, a move (joint or Cartesian) that would hit
    one is refused before anything moves (exit 1), unless --force; with --avoid it goes
    around them. A robot that touches an obstacle may move away from it.
    Ctrl-C or SIGTERM stops the robot (STOP_MOTION) and exits with 130 or 143.
    """
    target = target_from_options(kwargs)
    req = MoveRequest(**kwargs)
    req.check_usage()
    try:
        if req.avoid:
            need_obstacles(target.cell)
        goal = resolve_goal(target, req)
    except PymotorosError as exc:
        fail(exc, debug=target.debug)

    async def work() -> MoveResult:
        async with connected(target, motion=True, state=True, io=False) as client:
            await client.wait_for_state(target.timeout_s)
            if req.enable_first:
                await client.start_trajectory_mode()
            if not req.cartesian:  # the tool whose shape the obstacle check mounts
                use_tool(client, req.tool)
            _say_groups(client, req, goal)
            return await _move_watched(client, req, goal, target.timeout_s)

    result = run(target, work, stoppable=True)
    _report_move(result, req, goal, target.client().robot)


def _where(
    client: RobotClient,
    groups: tuple[int, ...],
    models: list[GroupModel],
    goal: tuple[float, ...],
    deg: bool,
    what: str,
) -> str:
    """Where the robot stands and how far it still is from the goal, in the user's units."""
    here = [v for g in groups for v in (client.state.positions(g) or ())]
    axes = [a for m in models for a in m.axes]
    if len(here) != len(axes):
        return f"{what}; position unknown (no joint feedback)"
    pos = joint_values_text(here, models, deg=deg)
    if len(here) != len(goal):  # a Cartesian move: the goal was a pose, say where the TCP is
        return f"{what} at {pos}{_tcp_where(client, groups[0])}"
    return f"{what} at {pos}, {_distance_left(here, goal, axes, deg)}"


def _distance_left(
    here: Sequence[float], goal: Sequence[float], axes: Sequence[Any], deg: bool
) -> str:
    """``1.5336 rad short of the goal (joint_1_s)``: the axis farthest from the goal, in
    its unit (rad or deg for a rotary axis, m or mm for a linear one)."""
    left, axis = max(
        ((abs(g - v), a) for g, v, a in zip(goal, here, axes, strict=True)),
        key=lambda pair: abs(to_user(pair[0], deg, pair[1].linear)),
    )
    return (
        f"{to_user(left, deg, axis.linear):.4f} {unit_of(deg, axis.linear)} "
        f"short of the goal ({axis.name})"
    )


def _short_of_goal(
    client: RobotClient, stopped_at: Sequence[float], goal: MoveGoal, deg: bool
) -> str:
    """What the CLI adds to the library's "stands at [...] rad" of a stopped move: with
    --deg the position in degrees, then how far from the goal (``; 1.5336 rad short of
    the goal (joint_1_s)``), or for a pose goal where the TCP is; never the position
    twice in the same unit."""
    axes = [a for m in goal.models for a in m.axes]
    if len(stopped_at) != len(axes):
        return ""
    said = [joint_values_text(stopped_at, goal.models, deg=True)] if deg else []
    if len(stopped_at) != len(goal.goal):  # a pose goal: where the TCP is
        said.append(_tcp_where(client, goal.groups[0]).strip(" ()"))
    else:
        said.append(_distance_left(stopped_at, goal.goal, axes, deg))
    said = [s for s in said if s]
    return f"; {', '.join(said)}" if said else ""


def _tcp_where(client: RobotClient, group: int) -> str:
    """`` (TCP x … y … z … mm in base)`` of the tool in force ("" when it cannot be known)."""
    try:
        x, y, z, *_ = client.tcp_pose(group)
    except PymotorosError:
        return ""
    return f" (TCP x {x * 1000:.1f} y {y * 1000:.1f} z {z * 1000:.1f} mm in base)"
