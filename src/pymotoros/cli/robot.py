"""Robot commands of the ``pymotoros`` CLI: status, enable, disable, move, stop, io, mreg, tool.

They drive a real MotoROS controller or ``pymotoros sim`` through the same async client
(:class:`pymotoros.client.RobotClient`). Errors print as one line on stderr (a
traceback only with ``--debug``) and end with a documented exit code.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import sys
import traceback
from collections.abc import AsyncIterator, Callable, Coroutine
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, TypeVar

import click

from pymotoros.client import (
    ClientError,
    ConnectError,
    ConnectionLostError,
    IoAddressError,
    RequestTimeoutError,
    RobotClient,
)
from pymotoros.client.planning import PlanningError
from pymotoros.client.srdf import NamedPoseError
from pymotoros.client.state import RobotState
from pymotoros.client.streaming import FollowingSample, MoveResult
from pymotoros.errors import ConfigError, PymotorosError
from pymotoros.models import DEFAULT_CONTROLLER, DEFAULT_ROBOT, ControllerType
from pymotoros.protocol.constants import TCP_PORT_IO, TCP_PORT_MOTION, TCP_PORT_STATE

EXIT_OK: Final = 0
EXIT_REFUSED: Final = 1
"""The robot refused or failed (NOT_READY, INVALID, IO result code, a move that did not finish)."""
EXIT_USAGE: Final = 2
"""Bad arguments: click's own usage errors, an IO address out of range, an unknown pose."""
EXIT_CONNECTION: Final = 3
"""No connection, connection lost, or no answer in time."""

EXIT_CODES_HELP: Final = (
    "\b\nExit codes:\n"
    "  0  done\n"
    "  1  the robot refused or failed (the message says why and what to do)\n"
    "  2  bad usage: options, IO address out of range, unknown pose\n"
    "  3  connection problem: refused, lost, or no answer in time"
)

_T = TypeVar("_T")
_F = TypeVar("_F", bound=Callable[..., Any])

_PORT = click.IntRange(1, 65535)


@dataclass(frozen=True, slots=True)
class Target:
    """Where the robot is and what it is (from the common options)."""

    host: str
    motion_port: int
    state_port: int
    io_port: int
    controller: str
    robot: str
    timeout_s: float
    debug: bool
    record: Path | None = None
    """pcapng file recording every frame of the session (--record)."""

    def client(self) -> RobotClient:
        return RobotClient(
            self.host,
            motion_port=self.motion_port,
            state_port=self.state_port,
            io_port=self.io_port,
            controller=self.controller,
            robot=self.robot,
            timeout_s=self.timeout_s,
            connect_timeout_s=self.timeout_s,
        )


@contextlib.asynccontextmanager
async def connected(
    target: Target, *, motion: bool, state: bool, io: bool
) -> AsyncIterator[RobotClient]:
    """A client connected to only the ports a command needs (MotoROS allows one motion and
    one IO connection: a command that does not need them leaves them to others)."""
    client = target.client()
    await client.connect(motion=motion, state=state, io=io)
    try:
        yield client
    finally:
        await client.close()


def robot_options(func: _F) -> _F:
    """The options every robot command takes."""
    options = [
        click.option("--host", default="127.0.0.1", show_default=True, help="Controller address."),
        click.option("--motion-port", type=_PORT, default=TCP_PORT_MOTION, show_default=True),
        click.option("--state-port", type=_PORT, default=TCP_PORT_STATE, show_default=True),
        click.option("--io-port", type=_PORT, default=TCP_PORT_IO, show_default=True),
        click.option(
            "--controller",
            type=click.Choice([t.value for t in ControllerType], case_sensitive=False),
            default=DEFAULT_CONTROLLER.value,
            show_default=True,
            help="Controller model: byte order (FS100 is big-endian) and IO map.",
        ),
        click.option(
            "--robot",
            default=DEFAULT_ROBOT,
            show_default=True,
            help="Robot model: joint names and limits.",
        ),
        click.option(
            "--timeout",
            "timeout_s",
            type=click.FloatRange(0.1, 600),
            default=5.0,
            show_default=True,
            help="Seconds to wait for a connection or a reply.",
        ),
        click.option("--debug", is_flag=True, help="Show a traceback on errors."),
        click.option(
            "--record",
            type=click.Path(dir_okay=False, writable=True, path_type=Path),
            default=None,
            help="Record every frame sent and received to this pcapng file (Wireshark).",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _target(kwargs: dict[str, Any]) -> Target:
    return Target(
        host=kwargs.pop("host"),
        motion_port=kwargs.pop("motion_port"),
        state_port=kwargs.pop("state_port"),
        io_port=kwargs.pop("io_port"),
        controller=kwargs.pop("controller"),
        robot=kwargs.pop("robot"),
        timeout_s=kwargs.pop("timeout_s"),
        debug=kwargs.pop("debug"),
        record=kwargs.pop("record", None),
    )


def _exit_code(exc: BaseException) -> int:
    if isinstance(exc, (ConnectError, ConnectionLostError, RequestTimeoutError)):
        return EXIT_CONNECTION
    if isinstance(exc, (IoAddressError, PlanningError, NamedPoseError, ConfigError)):
        return EXIT_USAGE
    if isinstance(exc, (ClientError, PymotorosError)):
        return EXIT_REFUSED
    return EXIT_REFUSED


def run(target: Target, work: Callable[[], Coroutine[Any, Any, _T]]) -> _T:
    """Run ``work`` on a fresh event loop; errors become one line and an exit code."""
    try:
        if target.record is None:
            return asyncio.run(work())
        from pymotoros.client.recorder import record_session

        with record_session(target.record):
            return asyncio.run(work())
    except (PymotorosError, OSError) as exc:
        if target.debug:
            traceback.print_exc()
        click.echo(f"error: {exc}", err=True)
        sys.exit(_exit_code(exc))
    except KeyboardInterrupt:
        click.echo("interrupted", err=True)
        sys.exit(130)


def _echo_json(data: object) -> None:
    click.echo(json.dumps(data))


# --------------------------------------------------------------------------- status


def _status_data(client: RobotClient, state: RobotState) -> dict[str, Any]:
    groups = []
    for index, group in enumerate(client.robot.groups):
        fb = state.joints.get(index)
        groups.append(
            {
                "group": index,
                "name": group.name,
                "joints": list(group.joint_names),
                "positions": list(fb.positions) if fb else None,
                "velocities": list(fb.velocities) if fb and fb.velocities else None,
            }
        )
    status = state.status.as_dict() if state.status else None
    return {"status": status, "groups": groups}


def _yes(value: bool | None, yes: str = "yes", no: str = "no") -> str:
    return "unknown" if value is None else (yes if value else no)


def _status_table(client: RobotClient, state: RobotState) -> str:
    lines = [f"{client.robot.name} on {client.controller.type.value} at {client.host}"]
    st = state.status
    if st is not None:
        lines += [
            f"  mode              {st.mode.value.upper()}",
            f"  servo power       {_yes(st.drives_powered, 'on', 'off')}",
            f"  e-stop            {_yes(st.e_stopped, 'PRESSED', 'released')}",
            f"  alarm             {st.error_code if st.in_error else 'none'}",
            f"  in motion         {_yes(st.in_motion)}",
            f"  motion possible   {_yes(st.motion_possible)}"
            + ("" if st.motion_possible else "  (pymotoros enable)"),
        ]
    width = max(len(n) for g in client.robot.groups for n in g.joint_names) + 2
    for index, group in enumerate(client.robot.groups):
        fb = state.joints.get(index)
        lines.append(f"  {group.name:<{width + 2}}{'rad':>10}{'deg':>10}{'rad/s':>10}")
        for j, name in enumerate(group.joint_names):
            if fb is None:
                lines.append(f"    {name:<{width}}{'-':>10}")
                continue
            pos = fb.positions[j]
            vel = fb.velocities[j] if fb.velocities else math.nan
            lines.append(f"    {name:<{width}}{pos:>10.4f}{math.degrees(pos):>10.2f}{vel:>10.4f}")
    return "\n".join(lines)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option("--watch", is_flag=True, help="Keep printing as the state changes (Ctrl-C ends).")
@click.option(
    "--count",
    type=click.IntRange(1),
    default=None,
    help="With --watch: stop after this many updates.",
)
@click.option(
    "--rate",
    type=click.FloatRange(0.1, 40),
    default=4.0,
    show_default=True,
    help="With --watch: updates per second at most.",
)
def status(as_json: bool, watch: bool, count: int | None, rate: float, **kwargs: Any) -> None:
    """Show the robot's state (state port only: safe next to another client)."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=False, state=True, io=False) as client:
            state = await client.wait_for_state(target.timeout_s)
            shown = 0
            last = -math.inf
            loop = asyncio.get_running_loop()
            while True:
                if loop.time() - last >= 1.0 / rate:
                    last = loop.time()
                    if as_json:
                        _echo_json(_status_data(client, state))
                    else:
                        click.echo(_status_table(client, state))
                    shown += 1
                    if not watch or (count is not None and shown >= count):
                        return
                state = await client.tracker.next_state(target.timeout_s)

    run(target, work)


# --------------------------------------------------------------------------- simple commands


def _motion_command(
    kwargs: dict[str, Any],
    call: Callable[[RobotClient], Coroutine[Any, Any, object]],
    done: str,
) -> None:
    """Run one motion-port command that needs neither state nor IO, then say ``done``."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=True, state=False, io=False) as client:
            await call(client)
        click.echo(done)

    run(target, work)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def enable(**kwargs: Any) -> None:
    """Enter trajectory mode: START_TRAJ_MODE (servo on, INIT_ROS started)."""
    _motion_command(
        kwargs,
        RobotClient.start_trajectory_mode,
        "trajectory mode on: the robot accepts motion",
    )


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def disable(**kwargs: Any) -> None:
    """Leave trajectory mode: STOP_TRAJ_MODE."""
    _motion_command(kwargs, RobotClient.stop_trajectory_mode, "trajectory mode off")


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def stop(**kwargs: Any) -> None:
    """Stop motion at once and clear every queue: STOP_MOTION."""
    _motion_command(kwargs, RobotClient.stop_motion, "stopped")


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0, 63))
@click.option("--group", type=click.IntRange(0, 3), default=0, show_default=True)
def tool(number: int, group: int, **kwargs: Any) -> None:
    """Select the tool file NUMBER (0..63) a group moves with: MOTO_SELECT_TOOL."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=True, state=False, io=False) as client:
            await client.select_tool(number, group)
        click.echo(f"group {group} moves with tool {number}")

    run(target, work)


# --------------------------------------------------------------------------- move


def _move_data(result: MoveResult) -> dict[str, Any]:
    return {
        "positions": list(result.final_positions),
        "elapsed_s": round(result.elapsed_s, 4),
        "planned_s": round(result.trajectory.duration, 4),
        "points": result.stream.points,
        "busy_replies": result.stream.busy_replies,
        "max_lag_s": round(result.following.max_lag_s, 4),
        "slowed": result.following.slowed,
    }


@click.command(epilog=EXIT_CODES_HELP, context_settings={"ignore_unknown_options": True})
@robot_options
@click.argument("joints", nargs=-1, type=float, metavar="[J1 ... Jn]")
@click.option("--named", "name", default=None, help="Move to a named pose instead (e.g. home).")
@click.option(
    "--srdf",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    default=None,
    help="SRDF file whose group_state entries are the named poses.",
)
@click.option("--deg", is_flag=True, help="J1 ... Jn are in degrees (default radians).")
@click.option(
    "--speed-scale",
    type=click.FloatRange(0.0, 1.0, min_open=True),
    default=1.0,
    show_default=True,
    help="Fraction of each joint's maximum velocity (like MoveIt's scaling factor).",
)
@click.option(
    "--accel-scale",
    type=click.FloatRange(0.0, 1.0, min_open=True),
    default=1.0,
    show_default=True,
    help="Fraction of each joint's maximum acceleration and jerk.",
)
@click.option("--group", type=click.IntRange(0, 3), default=0, show_default=True)
@click.option("--enable", "enable_first", is_flag=True, help="Enter trajectory mode first.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
def move(
    joints: tuple[float, ...],
    name: str | None,
    srdf: Path | None,
    deg: bool,
    speed_scale: float,
    accel_scale: float,
    group: int,
    enable_first: bool,
    as_json: bool,
    **kwargs: Any,
) -> None:
    """Move to joint positions J1 ... Jn (rad) or to a named pose, with a progress bar.

    Starts from where the robot rests, plans a synchronised, jerk-limited move within
    the robot model's limits and waits until the robot has settled at the goal.
    Ctrl-C stops the robot (STOP_MOTION).
    """
    target = _target(kwargs)
    if (name is None) == (not joints):
        raise click.UsageError("give either joint values J1 ... Jn or --named NAME")
    if srdf is not None and name is None:
        raise click.UsageError("--srdf goes with --named")

    async def work() -> MoveResult:
        async with connected(target, motion=True, state=True, io=False) as client:
            if name is not None:
                goal = client.named_pose(name, srdf=srdf, group=group)
            else:
                axes = client.robot.groups[group].num_axes
                if len(joints) != axes:
                    names = ", ".join(client.robot.groups[group].joint_names)
                    raise PlanningError(f"{client.robot.name} needs {axes} values ({names})")
                goal = tuple(math.radians(j) for j in joints) if deg else joints
            if enable_first:
                await client.start_trajectory_mode()
            bar = (
                click.progressbar(length=1000, label="moving", file=sys.stderr, show_eta=False)
                if sys.stderr.isatty()
                else None
            )
            done = [0]

            def progress(sample: FollowingSample) -> None:
                now = int(sample.progress * 1000)
                if bar is not None and now > done[0]:
                    bar.update(now - done[0])
                    done[0] = now

            with bar if bar is not None else contextlib.nullcontext():
                try:
                    result = await client.move_joints(
                        goal,
                        group=group,
                        speed_scale=speed_scale,
                        accel_scale=accel_scale,
                        on_progress=progress,
                    )
                except asyncio.CancelledError:
                    with contextlib.suppress(PymotorosError):
                        await asyncio.shield(client.stop_motion())
                    raise
                if bar is not None:
                    bar.update(1000 - done[0])
            return result

    result = run(target, work)
    if as_json:
        _echo_json(_move_data(result))
    else:
        pos = ", ".join(f"{p:.4f}" for p in result.final_positions)
        click.echo(
            f"reached [{pos}] in {result.elapsed_s:.2f} s "
            f"(planned {result.trajectory.duration:.2f} s, {result.stream.points} points)"
        )
        if result.following.slowed:
            click.echo(
                f"note: the robot ran up to {result.following.max_lag_s:.2f} s behind the plan "
                "(a safety speed limit or override slowed it)"
            )


# --------------------------------------------------------------------------- io and mreg


@click.group(epilog=EXIT_CODES_HELP)
def io() -> None:
    """Read or write an IO bit (or a group of 8 with --group).

    \b
    Bit addresses end in the bit number 0..7: 10010 is general output OT#1,
    10011 OT#2 … A group address is the bit address without its last digit
    (1001 = bits 10010..10017). Leading zeros are ignored (decimal, not octal).
    MotoROS writes only general outputs, network inputs and the interface panel;
    addresses are checked against --controller's IO map before anything is sent.
    """


@io.command("read", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("address", type=click.IntRange(0))
@click.option("--group", "as_group", is_flag=True, help="ADDRESS is a group (byte) address.")
@click.option("--json", "as_json", is_flag=True, help='Print {"address": A, "value": V}.')
def io_read(address: int, as_group: bool, as_json: bool, **kwargs: Any) -> None:
    """Read the IO bit (or group) at ADDRESS."""
    target = _target(kwargs)

    async def work() -> int:
        async with connected(target, motion=False, state=False, io=True) as client:
            if as_group:
                return await client.read_io_group(address)
            return await client.read_io_bit(address)

    value = run(target, work)
    if as_json:
        _echo_json({"address": address, "value": value})
    else:
        click.echo(str(value))


@io.command("write", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("address", type=click.IntRange(0))
@click.argument("value", type=click.IntRange(0))
@click.option("--group", "as_group", is_flag=True, help="ADDRESS is a group (byte) address.")
@click.option("--json", "as_json", is_flag=True, help='Print {"address": A, "value": V}.')
def io_write(address: int, value: int, as_group: bool, as_json: bool, **kwargs: Any) -> None:
    """Write VALUE (0/1, or 0..255 with --group) to the IO bit (or group) at ADDRESS."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=False, state=False, io=True) as client:
            if as_group:
                await client.write_io_group(address, value)
            else:
                await client.write_io_bit(address, value)

    run(target, work)
    if as_json:
        _echo_json({"address": address, "value": value})
    else:
        click.echo(f"{address} = {value}")


@click.group(epilog=EXIT_CODES_HELP)
def mreg() -> None:
    """Read or write an M-register (read M000-M999, write M000-M559; 16 bits).

    Give the plain number (10 for M010), not 1000000 + n.
    """


@mreg.command("read", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0))
@click.option("--json", "as_json", is_flag=True, help='Print {"number": N, "value": V}.')
def mreg_read(number: int, as_json: bool, **kwargs: Any) -> None:
    """Read M-register NUMBER."""
    target = _target(kwargs)

    async def work() -> int:
        async with connected(target, motion=False, state=False, io=True) as client:
            return await client.read_mregister(number)

    value = run(target, work)
    if as_json:
        _echo_json({"number": number, "value": value})
    else:
        click.echo(str(value))


@mreg.command("write", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0))
@click.argument("value", type=click.IntRange(0))
@click.option("--json", "as_json", is_flag=True, help='Print {"number": N, "value": V}.')
def mreg_write(number: int, value: int, as_json: bool, **kwargs: Any) -> None:
    """Write VALUE (0..65535) to M-register NUMBER."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=False, state=False, io=True) as client:
            await client.write_mregister(number, value)

    run(target, work)
    if as_json:
        _echo_json({"number": number, "value": value})
    else:
        click.echo(f"M{number:03d} = {value}")


__all__ = ["disable", "enable", "io", "move", "mreg", "status", "stop", "tool"]
