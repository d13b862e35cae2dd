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
import signal
import sys
import traceback
from collections.abc import AsyncIterator, Callable, Coroutine, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, NoReturn, TypeVar

import click

from pymotoros.cli.cartesian import cartesian_move, parse_relative, pose_from_args
from pymotoros.cli.live import FrameWriter, alarm_line, not_ready_reason, twin_alarm_texts
from pymotoros.cli.ports_file import ports_file_target, read_ports
from pymotoros.cli.settings import cell_option, envvar
from pymotoros.cli.sim_view import fetch_state_async, safety_data, safety_lines
from pymotoros.client import (
    ClientError,
    ConnectError,
    ConnectionLostError,
    GroupError,
    IoAddressError,
    ModelMismatchError,
    ReplyError,
    RequestTimeoutError,
    RobotClient,
)
from pymotoros.client.planning import PlanningError
from pymotoros.client.srdf import NamedPoseError
from pymotoros.client.state import RobotState
from pymotoros.client.streaming import FollowingSample, MoveResult
from pymotoros.errors import ConfigError, PymotorosError
from pymotoros.models import DEFAULT_CONTROLLER, DEFAULT_ROBOT, ControllerType, GroupModel
from pymotoros.models.cell import CellModels
from pymotoros.protocol.constants import (
    MAX_TOOL_NUMBER,
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    TCP_PORT_STATE,
)

EXIT_OK: Final = 0
EXIT_REFUSED: Final = 1
"""The robot refused or failed (NOT_READY, INVALID, IO result code, a move that did not finish)."""
EXIT_USAGE: Final = 2
"""Bad arguments: click's own usage errors, an IO address out of range, an unknown pose."""
EXIT_CONNECTION: Final = 3
"""No connection, connection lost, or no answer in time."""
EXIT_INTERRUPTED: Final = 130
"""Ctrl-C (SIGINT): a moving robot was stopped with STOP_MOTION first (128 + signal 2)."""
EXIT_TERMINATED: Final = 143
"""SIGTERM: a moving robot was stopped with STOP_MOTION first (128 + signal 15)."""

EXIT_CODES_HELP: Final = (
    "\b\nExit codes:\n"
    "  0    done\n"
    "  1    the robot refused or failed (the message says why and what to do)\n"
    "  2    bad usage: options, values, IO address, unknown pose or group, model mismatch\n"
    "  3    connection problem: refused, lost, or no answer in time\n"
    "  130  Ctrl-C (a moving robot is stopped first)\n"
    "  143  SIGTERM (a moving robot is stopped first)"
)

_T = TypeVar("_T")
_F = TypeVar("_F", bound=Callable[..., Any])

_PORT = click.IntRange(1, 65535)
_DEFAULT_PORTS: Final = {"motion": TCP_PORT_MOTION, "state": TCP_PORT_STATE, "io": TCP_PORT_IO}


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
    cell: Path | CellModels | None = None
    """A cell file (``--config``), or the cell a ports file describes: controller and
    groups, instead of --controller/--robot."""
    http_port: int | None = None
    """The twin's control API port, when a ports file told it."""
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
            cell=self.cell,
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
    """The options every robot command takes (each also from ``PYMOTOROS_<NAME>``).

    Ports left unset come from ``--ports-file`` (written by ``pymotoros sim
    --ports-file``), else MotoROS's fixed ports.
    """
    options = [
        click.option(
            "--host",
            default="127.0.0.1",
            show_default=True,
            envvar=envvar("host"),
            help="Controller address.",
        ),
        click.option(
            "--motion-port",
            type=_PORT,
            default=None,
            envvar=envvar("motion_port"),
            help=f"[default: {TCP_PORT_MOTION}]",
        ),
        click.option(
            "--state-port",
            type=_PORT,
            default=None,
            envvar=envvar("state_port"),
            help=f"[default: {TCP_PORT_STATE}]",
        ),
        click.option(
            "--io-port",
            type=_PORT,
            default=None,
            envvar=envvar("io_port"),
            help=f"[default: {TCP_PORT_IO}]",
        ),
        click.option(
            "--ports-file",
            type=click.Path(dir_okay=False, path_type=Path),
            default=None,
            envvar=envvar("ports_file"),
            help="JSON file written by `pymotoros sim --ports-file`: the ports of a port-0 twin.",
        ),
        click.option(
            "--controller",
            type=click.Choice([t.value for t in ControllerType], case_sensitive=False),
            default=DEFAULT_CONTROLLER.value,
            show_default=True,
            envvar=envvar("controller"),
            help="Controller model: byte order (FS100 is big-endian) and IO map.",
        ),
        click.option(
            "--robot",
            default=DEFAULT_ROBOT,
            show_default=True,
            envvar=envvar("robot"),
            help="Robot model: joint names and limits.",
        ),
        click.option(
            "--config",
            "cell_path",
            type=click.Path(exists=True, dir_okay=False, path_type=Path),
            default=None,
            envvar=envvar("config"),
            metavar="CELL.toml",
            help="Cell file (the sim's format) naming controller and groups; replaces "
            "--controller/--robot.",
        ),
        click.option(
            "--timeout",
            "timeout_s",
            type=click.FloatRange(0.1, 600),
            default=5.0,
            show_default=True,
            envvar=envvar("timeout"),
            help="Seconds to wait for a connection or a reply.",
        ),
        click.option(
            "--debug", is_flag=True, envvar=envvar("debug"), help="Show a traceback on errors."
        ),
        click.option(
            "--record",
            type=click.Path(dir_okay=False, writable=True, path_type=Path),
            default=None,
            envvar=envvar("record"),
            help="Record every frame sent and received to this pcapng file (Wireshark).",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return cell_option(func)


def group_option(*, multiple: bool = False, default: str | None = "0") -> Callable[[_F], _F]:
    """``--group`` by name (R1, R2, B1 … as the pendant names them) or number (0, 1 …)."""
    help_text = "Control group: name (R1, R2, B1 …) or number (0, 1 …)" + (
        "; repeat to move several groups in one trajectory (values in group order)."
        if multiple
        else "."
    )
    return click.option(
        "--group",
        "group",
        multiple=multiple,
        default=() if multiple else default,
        show_default=not multiple,
        metavar="NAME|N",
        help=help_text,
    )


def unit_of(deg: bool, linear: bool = False) -> str:
    return "m" if linear else ("deg" if deg else "rad")


def to_user(value: float, deg: bool, linear: bool = False) -> float:
    return value if linear or not deg else math.degrees(value)


def read_ports_file(path: Path) -> dict[str, int]:
    """The ports a ``pymotoros sim --ports-file`` wrote (motion, state, io, http)."""
    return read_ports(path)


def _target(kwargs: dict[str, Any]) -> Target:
    debug = kwargs.pop("debug")
    ports_file: Path | None = kwargs.pop("ports_file")
    try:
        told = ports_file_target(ports_file, kwargs.pop("cell"))
    except ConfigError as exc:
        fail(exc, debug=debug)
    from_file = told.ports

    def port(kind: str) -> int:
        given: int | None = kwargs.pop(f"{kind}_port")
        return given if given is not None else from_file.get(kind, _DEFAULT_PORTS[kind])

    cell = kwargs.get("cell_path")
    ctx = click.get_current_context(silent=True)
    named_by = f"the cell file {cell}" if cell is not None else told.named_by(ports_file)
    if named_by is not None and ctx is not None:
        for option in ("controller", "robot"):
            if ctx.get_parameter_source(option) is click.core.ParameterSource.COMMANDLINE:
                click.echo(f"warning: --{option} is ignored: {named_by} names the models", err=True)
    return Target(
        host=kwargs.pop("host"),
        motion_port=port("motion"),
        state_port=port("state"),
        io_port=port("io"),
        controller=kwargs.pop("controller"),
        robot=kwargs.pop("robot"),
        timeout_s=kwargs.pop("timeout_s"),
        debug=debug,
        cell=kwargs.pop("cell_path") or told.models,
        http_port=from_file.get("http"),
        record=kwargs.pop("record", None),
    )


def _exit_code(exc: BaseException) -> int:
    if isinstance(exc, (ConnectError, ConnectionLostError, RequestTimeoutError)):
        return EXIT_CONNECTION
    if isinstance(
        exc,
        (
            IoAddressError,
            PlanningError,
            NamedPoseError,
            ConfigError,
            GroupError,
            ModelMismatchError,
            InputError,
        ),
    ):
        return EXIT_USAGE
    if isinstance(exc, (ClientError, PymotorosError)):
        return EXIT_REFUSED
    return EXIT_REFUSED


class InputError(PymotorosError, ValueError):
    """A value the user typed that cannot be right (NaN, beyond a limit): exit code 2."""


def fail(exc: BaseException, *, debug: bool) -> NoReturn:
    """One line on stderr (a traceback too with --debug) and the error's exit code."""
    if debug:
        traceback.print_exception(exc)
    click.echo(f"error: {exc}", err=True)
    sys.exit(_exit_code(exc))


def run(
    target: Target, work: Callable[[], Coroutine[Any, Any, _T]], *, stoppable: bool = False
) -> _T:
    """Run ``work`` on a fresh event loop; errors become one line and an exit code.

    With ``stoppable`` (commands that move the robot), SIGTERM cancels ``work`` like
    Ctrl-C does: ``work`` sends STOP_MOTION on cancellation, then the process exits
    with :data:`EXIT_TERMINATED` (:data:`EXIT_INTERRUPTED` for Ctrl-C).
    """
    signals: list[int] = []

    async def main() -> _T:
        task = asyncio.current_task()
        loop = asyncio.get_running_loop()
        if stoppable and task is not None:

            def on_signal(sig: int) -> None:
                signals.append(sig)
                task.cancel()

            for sig in (signal.SIGTERM, signal.SIGINT):
                with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                    loop.add_signal_handler(sig, on_signal, sig)
        return await work()

    try:
        if target.record is None:
            return asyncio.run(main())
        from pymotoros.client.recorder import record_session

        with record_session(target.record):
            return asyncio.run(main())
    except (PymotorosError, OSError) as exc:
        fail(exc, debug=target.debug)
    except (KeyboardInterrupt, asyncio.CancelledError):
        code = EXIT_TERMINATED if signal.SIGTERM in signals else EXIT_INTERRUPTED
        click.echo("interrupted", err=True)
        sys.exit(code)


def _echo_json(data: object) -> None:
    click.echo(json.dumps(data))


# --------------------------------------------------------------------------- status


def _status_data(
    client: RobotClient, state: RobotState, only: tuple[int, ...] = ()
) -> dict[str, Any]:
    groups = []
    for index, group in enumerate(client.robot.groups):
        if only and index not in only:
            continue
        fb = state.joints.get(index)
        groups.append(
            {
                "group": index,
                "name": group.name,
                "joints": list(group.joint_names),
                "positions": list(fb.positions) if fb else None,
                "velocities": list(fb.velocities) if fb and fb.velocities else None,
                "tcp": _tcp_or_none(client, index),
            }
        )
    status = state.status.as_dict() if state.status else None
    if status is not None and state.status is not None and not state.status.motion_possible:
        status["not_ready_reason"] = not_ready_reason(state.status)
    return {"status": status, "groups": groups}


def _tcp_or_none(client: RobotClient, group: int) -> list[float] | None:
    """The TCP pose in base coordinates (m, rad), or None without feedback or chain."""
    try:
        return list(client.tcp_pose(group))
    except PymotorosError:
        return None


def _yes(value: bool | None, yes: str = "yes", no: str = "no") -> str:
    return "unknown" if value is None else (yes if value else no)


def _status_table(
    client: RobotClient,
    state: RobotState,
    only: tuple[int, ...] = (),
    alarm_texts: dict[int, str] | None = None,
    sim_state: dict[str, Any] | None = None,
) -> str:
    lines = [f"{client.robot.name} on {client.controller.type.value} at {client.host}"]
    st = state.status
    if st is not None:
        lines += [
            f"  mode              {st.mode.value.upper()}",
            f"  servo power       {_yes(st.drives_powered, 'on', 'off')}",
            f"  e-stop            {_yes(st.e_stopped, 'PRESSED', 'released')}",
            f"  alarm             {alarm_line(st, alarm_texts or {})}",
            f"  in motion         {_yes(st.in_motion)}",
            f"  motion possible   {_yes(st.motion_possible)}"
            + ("" if st.motion_possible else f"  ({not_ready_reason(st)})"),
        ]
    lines += safety_lines(sim_state, st.error_code if st is not None and st.in_error else None)
    width = max(len(n) for g in client.robot.groups for n in g.joint_names) + 2
    for index, group in enumerate(client.robot.groups):
        if only and index not in only:
            continue
        fb = state.joints.get(index)
        lines.append(f"  {group.name:<{width + 2}}{'rad':>10}{'deg':>10}{'rad/s':>10}")
        for j, name in enumerate(group.joint_names):
            if fb is None:
                lines.append(f"    {name:<{width}}{'-':>10}")
                continue
            pos = fb.positions[j]
            vel = fb.velocities[j] if fb.velocities else math.nan
            lines.append(f"    {name:<{width}}{pos:>10.4f}{math.degrees(pos):>10.2f}{vel:>10.4f}")
        tcp = _tcp_or_none(client, index)
        if tcp is not None:
            x, y, z, rx, ry, rz = tcp
            lines.append(
                f"    {'TCP (base)':<{width}}x {x * 1000:.1f} y {y * 1000:.1f} z {z * 1000:.1f} mm"
                f"  Rx {math.degrees(rx):.2f} Ry {math.degrees(ry):.2f} Rz {math.degrees(rz):.2f}"
                " deg"
            )
    return "\n".join(lines)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option(
    "--watch",
    is_flag=True,
    help="Keep showing the state as it changes (Ctrl-C ends): redrawn in place on a "
    "terminal, else printed when it changes (every update with --json).",
)
@click.option(
    "--live/--no-live",
    default=None,
    help="With --watch: redraw in place (default: when stdout is a terminal).",
)
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
@group_option(multiple=True)
@click.option(
    "--check-model",
    is_flag=True,
    help="Also compare the controller's DH parameters with the robot model (opens the "
    "motion port: not next to a moving client).",
)
@click.option(
    "--api",
    default=None,
    metavar="URL",
    help="pymotoros sim's control API (e.g. http://127.0.0.1:8080): adds PFL, FSU, alarm texts.",
)
def status(
    as_json: bool,
    watch: bool,
    live: bool | None,
    count: int | None,
    rate: float,
    group: tuple[str, ...],
    check_model: bool,
    api: str | None,
    **kwargs: Any,
) -> None:
    """Show the robot's state (state port only: safe next to another client)."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=check_model, state=True, io=False) as client:
            only = tuple(client.group_index(g) for g in group)
            state = await client.wait_for_state(target.timeout_s)
            if check_model:
                await client.check_dh_parameters()
            shown = 0
            last = -math.inf
            loop = asyncio.get_running_loop()
            texts: dict[int, str] = {}
            redraw = watch and not as_json and (sys.stdout.isatty() if live is None else live)
            frames = FrameWriter(sys.stdout, live=redraw)
            try:
                while True:
                    if loop.time() - last >= 1.0 / rate:
                        last = loop.time()
                        st = state.status
                        if st is not None and st.in_error and st.error_code not in texts:
                            texts.update(
                                await asyncio.to_thread(
                                    twin_alarm_texts, target.host, target.http_port
                                )
                            )
                        sim_state = await fetch_state_async(api) if api is not None else None
                        if as_json:
                            _echo_json(_status_data(client, state, only) | safety_data(sim_state))
                            shown += 1
                        elif frames.show(_status_table(client, state, only, texts, sim_state)):
                            shown += 1
                        if not watch or (count is not None and shown >= count):
                            return
                    state = await client.tracker.next_state(target.timeout_s)
            finally:
                frames.close()

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


ONE_MOTION_CLIENT: Final = (
    "MotoROS allows one motion client and closes a second motion connection while the "
    "robot moves, so `pymotoros stop` cannot take over. What works: Ctrl-C in the "
    "terminal of the moving command (or SIGTERM to it: it sends STOP_MOTION), HOLD or "
    "E-stop on the pendant, or for the twin its control API "
    '(POST /api/hold {{"on": true}} or /api/estop {{"pressed": true}} on {api})'
)
"""Reference §2.1: one motion connection; a new one is closed while increments are queued."""


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def stop(**kwargs: Any) -> None:
    """Stop motion at once and clear every queue: STOP_MOTION.

    Only when no other client holds the motion connection: MotoROS refuses a second
    motion client while the robot moves (the message says what works instead).
    """
    target = _target(kwargs)

    async def work() -> None:
        try:
            async with connected(target, motion=True, state=False, io=False) as client:
                await client.stop_motion()
        except ConnectionLostError as exc:
            api = (
                f"http://{target.host}:{target.http_port}"
                if target.http_port is not None
                else "the sim's --http-port"
            )
            raise ConnectionLostError(f"{exc}. " + ONE_MOTION_CLIENT.format(api=api)) from exc
        click.echo("stopped")

    run(target, work)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def reset(**kwargs: Any) -> None:
    """Reset alarms and cancel errors: RESET_ALARM (the cause must be gone first)."""
    _motion_command(kwargs, RobotClient.reset_alarm, "alarms and errors reset")


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("state", type=click.Choice(["on", "off"], case_sensitive=False))
def servo(state: str, **kwargs: Any) -> None:
    """Servo power on or off: START_SERVOS / STOP_SERVOS (trajectory mode is separate)."""
    if state.lower() == "on":
        _motion_command(kwargs, RobotClient.start_servos, "servo power on")
    else:
        _motion_command(kwargs, RobotClient.stop_servos, "servo power off")


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0, MAX_TOOL_NUMBER))
@group_option()
def tool(number: int, group: str, **kwargs: Any) -> None:
    """Select the tool file NUMBER (0..63, §5.8) a group moves with: MOTO_SELECT_TOOL."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=True, state=False, io=False) as client:
            index = client.group_index(group)
            await client.select_tool(number, index)
        click.echo(f"group {index} ({client.robot.groups[index].name}) moves with tool {number}")

    run(target, work)


# --------------------------------------------------------------------------- move


@contextlib.contextmanager
def progress_bar(label: str) -> Iterator[Callable[[FollowingSample], None]]:
    """A progress bar on a terminal's stderr, fed by the following monitor's samples;
    nothing when stderr is not a terminal. Completed only if the block succeeds."""
    if not sys.stderr.isatty():
        yield lambda _sample: None
        return
    with click.progressbar(length=1000, label=label, file=sys.stderr, show_eta=False) as bar:
        done = [0]

        def progress(sample: FollowingSample) -> None:
            now = int(sample.progress * 1000)
            if now > done[0]:
                bar.update(now - done[0])
                done[0] = now

        yield progress
        bar.update(1000 - done[0])


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
@click.option(
    "--deg", is_flag=True, help="J1 ... Jn, results and limit errors in degrees (default radians)."
)
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
@group_option(multiple=True)
@click.option("--enable", "enable_first", is_flag=True, help="Enter trajectory mode first.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@click.option(
    "--pose",
    "as_pose",
    is_flag=True,
    help="The values are a TCP pose X Y Z (m) RX RY RZ (rad; deg with --deg) in base "
    "coordinates, R = Rz·Ry·Rx; a joint move unless --linear.",
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
def move(
    joints: tuple[float, ...],
    name: str | None,
    srdf: Path | None,
    deg: bool,
    speed_scale: float,
    accel_scale: float,
    group: tuple[str, ...],
    enable_first: bool,
    as_json: bool,
    as_pose: bool = False,
    linear: bool = False,
    relative: tuple[str, ...] = (),
    frame: str = "base",
    tcp_speed_mm_s: float = 250.0,
    **kwargs: Any,
) -> None:
    """Move to joint positions J1 ... Jn (rad, or deg with --deg) or to a named pose.

    Starts from where the robot rests, plans a synchronised, jerk-limited move within
    the robot model's limits and waits until the robot has settled at the goal. With
    several --group options the values are the groups' joints one group after the
    other, sent as one JOINT_TRAJ_PT_FULL_EX trajectory. Ctrl-C or SIGTERM stops the
    robot (STOP_MOTION) and exits with 130 or 143.
    """
    target = _target(kwargs)
    cartesian = as_pose or bool(relative)
    if linear and not as_pose:
        raise click.UsageError("--linear goes with --pose (--relative moves are always straight)")
    if as_pose and (relative or name is not None):
        raise click.UsageError("give one target: --pose, --relative or --named")
    if relative and joints:
        raise click.UsageError("--relative takes no positional values")
    if not cartesian and (name is None) == (not joints):
        raise click.UsageError("give either joint values J1 ... Jn or --named NAME")
    if srdf is not None and name is None:
        raise click.UsageError("--srdf goes with --named")
    unit = "deg" if deg else "rad"
    rel = parse_relative(relative, deg) if relative else None
    pose = pose_from_args(joints, deg) if as_pose else None

    try:  # the goal is checked against the model before anything is sent
        model_client = target.client()
        groups = tuple(model_client.group_index(g) for g in group) or (0,)
        if len(set(groups)) != len(groups):
            raise InputError("a --group is given twice: give each group once")
        models = [model_client.robot.groups[g] for g in groups]
        if cartesian:
            if len(groups) != 1:
                raise InputError("a Cartesian move (--pose, --relative) takes one --group")
            goal: tuple[float, ...] = ()
        elif name is not None:
            goal = tuple(
                v for g in groups for v in model_client.named_pose(name, srdf=srdf, group=g)
            )
        else:
            goal = _goal_from_values(joints, models, deg)
    except PymotorosError as exc:
        fail(exc, debug=target.debug)

    async def work() -> MoveResult:
        async with connected(target, motion=True, state=True, io=False) as client:
            await client.wait_for_state(target.timeout_s)
            if enable_first:
                await client.start_trajectory_mode()
            with progress_bar("moving") as progress:
                try:
                    if cartesian:
                        result = await cartesian_move(
                            client,
                            pose=pose,
                            relative=rel,
                            linear=linear or rel is not None,
                            frame="tool" if frame == "tool" else "base",
                            tcp_speed_mm_s=tcp_speed_mm_s,
                            group=groups[0],
                            speed_scale=speed_scale,
                            accel_scale=accel_scale,
                            on_progress=progress,
                        )
                    else:
                        start = await client.current_positions(groups)
                        trajectory = client.plan(
                            start,
                            goal,
                            groups=groups,
                            speed_scale=speed_scale,
                            accel_scale=accel_scale,
                        )
                        result = await client.execute(
                            trajectory, groups=groups, on_progress=progress
                        )
                except asyncio.CancelledError:
                    with contextlib.suppress(PymotorosError):
                        await asyncio.shield(client.stop_motion())
                    click.echo(
                        "\n" + _where(client, groups, models, goal, deg, "stopped (STOP_MOTION)"),
                        err=True,
                    )
                    raise
                except ReplyError as exc:
                    if exc.point is not None:  # refused mid-move: say where the robot is
                        where = _where(client, groups, models, goal, deg, "the robot stands")
                        exc.args = (f"{exc}; {where}", *exc.args[1:])
                    raise
            return result

    result = run(target, work, stoppable=True)
    if as_json:
        _echo_json(_move_data(result))
    else:
        pos = ", ".join(f"{to_user(p, deg):.4f}" for p in result.final_positions)
        click.echo(
            f"reached [{pos}] {unit} in {result.elapsed_s:.2f} s "
            f"(planned {result.trajectory.duration:.2f} s, {result.stream.points} points)"
        )
        if result.following.slowed:
            click.echo(
                f"note: the robot ran up to {result.following.max_lag_s:.2f} s behind the plan "
                "(a safety speed limit or override slowed it)"
            )


def _goal_from_values(
    values: tuple[float, ...], models: list[GroupModel], deg: bool
) -> tuple[float, ...]:
    """The goal in rad/m from the user's values, each checked: count, NaN, limits."""
    axes = [a for m in models for a in m.axes]
    if len(values) != len(axes):
        needs = "; ".join(f"{m.name}: {m.num_axes} ({', '.join(m.joint_names)})" for m in models)
        raise InputError(
            f"{len(values)} values given, {len(axes)} needed ({needs}); "
            "repeat --group to move several groups"
        )
    goal = []
    for value, axis in zip(values, axes, strict=True):
        u = unit_of(deg, axis.linear)
        if not math.isfinite(value):
            raise InputError(f"{axis.name}: {value} is not a number; give a finite value in {u}")
        v = value if axis.linear or not deg else math.radians(value)
        if not axis.lower <= v <= axis.upper:
            lo, hi = to_user(axis.lower, deg, axis.linear), to_user(axis.upper, deg, axis.linear)
            raise InputError(
                f"{axis.name}: {value:g} {u} is outside its limits "
                f"[{lo:.4g}, {hi:.4g}] {u}; give a value within them"
                + ("" if deg or axis.linear else " (values in degrees need --deg)")
            )
        goal.append(v)
    return tuple(goal)


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
    if len(here) != len(goal):
        return f"{what}; position unknown"
    axes = [a for m in models for a in m.axes]
    pos = ", ".join(f"{to_user(v, deg, a.linear):.4f}" for v, a in zip(here, axes, strict=True))
    left = max(
        (abs(to_user(g - v, deg, a.linear)), a.name)
        for g, v, a in zip(goal, here, axes, strict=True)
    )
    return (
        f"{what} at [{pos}] {'deg' if deg else 'rad'}, {left[0]:.4f} "
        f"{'deg' if deg else 'rad'} short of the goal ({left[1]})"
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
