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
import shutil
import signal
import sys
import traceback
from collections.abc import AsyncIterator, Callable, Coroutine, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Final, NoReturn, TypeVar

import click

from pymotoros.cli.cartesian import (
    cartesian_move,
    parse_relative,
    pose_from_args,
    tcp_data,
    tcp_lines,
    tool_option,
    use_tool,
)
from pymotoros.cli.live import (
    FrameWriter,
    OnceWriter,
    alarm_line,
    not_ready_reason,
    twin_alarm_texts,
)
from pymotoros.cli.options import (
    EXIT_CONNECTION,
    EXIT_USAGE,
    InputFile,
    NumbersCommand,
    deg_option,
    enable_option,
    group_option,
    json_option,
    robot_options,
    scale_options,
    token_option,
)
from pymotoros.cli.ports_file import ports_file_target, read_ports
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
from pymotoros.client.errors import SECOND_MOTION_CLIENT
from pymotoros.client.planning import JointTrajectory, PlanningError
from pymotoros.client.srdf import NamedPoseError
from pymotoros.client.state import RobotState
from pymotoros.client.streaming import FollowingSample, MoveResult, joint_values_text
from pymotoros.errors import ConfigError, PathBlockedError, PymotorosError
from pymotoros.models import GroupModel
from pymotoros.models.cell import CellModels, load_cell_models
from pymotoros.protocol.constants import (
    MAX_TOOL_NUMBER,
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    TCP_PORT_STATE,
)

EXIT_OK: Final = 0
EXIT_REFUSED: Final = 1
"""The robot refused or failed (NOT_READY, INVALID, IO result code, a move that did not finish)."""
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


class MoveBlockedError(PymotorosError):
    """The planned move hits an obstacle of the cell (or the arm itself): exit code 1,
    nothing sent."""


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
            }
            | tcp_data(client, index)
        )
    status = state.status.as_dict() if state.status else None
    if status is not None and state.status is not None and not state.status.motion_possible:
        status["not_ready_reason"] = not_ready_reason(state.status)
    return {"status": status, "groups": groups}


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
        lines += tcp_lines(client, index, width)
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
    help="With --watch: stop after this many updates (at --rate; an update that changes "
    "nothing is not printed again off a terminal, but counts).",
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
@token_option
@tool_option
def status(
    as_json: bool,
    watch: bool,
    live: bool | None,
    count: int | None,
    rate: float,
    group: tuple[str, ...],
    check_model: bool,
    api: str | None,
    token: str | None = None,
    tool: int | None = None,
    **kwargs: Any,
) -> None:
    """Show the robot's state (state port only: safe next to another client)."""
    target = _target(kwargs)

    async def work() -> None:
        async with connected(target, motion=check_model, state=True, io=False) as client:
            use_tool(client, tool)
            only = tuple(client.group_index(g) for g in group)
            state = await client.wait_for_state(target.timeout_s)
            if check_model:
                await client.check_dh_parameters()
            shown = 0
            last = -math.inf
            loop = asyncio.get_running_loop()
            texts: dict[int, str] = {}
            warned = OnceWriter()  # a refused alarm-text request: told once, not per frame
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
                                    twin_alarm_texts,
                                    target.host,
                                    target.http_port,
                                    token,
                                    warned.tell_once,
                                )
                            )
                        sim_state = await fetch_state_async(api, token) if api is not None else None
                        if as_json:
                            _echo_json(_status_data(client, state, only) | safety_data(sim_state))
                        else:  # an unchanged frame is not printed again, but counts
                            frames.show(_status_table(client, state, only, texts, sim_state))
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

STOP_ELSEWHERE: Final = (
    "That is why `pymotoros stop` cannot take over. SIGTERM to the moving command works "
    "as well (it sends STOP_MOTION), so does E-stop on the pendant and, for the twin, its "
    'control API (POST /api/hold {{"on": true}} or /api/estop {{"pressed": true}} on {api})'
)
"""What ``stop`` adds when the library's message already states the one-client rule and
the Ctrl-C/HOLD remedies (:data:`~pymotoros.client.errors.SECOND_MOTION_CLIENT`)."""


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
            rule_told = SECOND_MOTION_CLIENT in str(exc)  # say the rule once, not twice
            more = (STOP_ELSEWHERE if rule_told else ONE_MOTION_CLIENT).format(api=api)
            raise ConnectionLostError(f"{exc}. {more}") from exc
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

PROGRESS_REDRAW_S: Final = 0.1
"""Shortest time between two redraws of a terminal's progress line."""
SETTLE_TIMEOUT_S: Final = 3.0
"""How long a refused or stopped move waits for the robot to come to rest before it says
where the robot stands (an E-stop's braking takes well under a second)."""


def progress_line(
    label: str,
    sample: FollowingSample,
    positions: Sequence[float],
    *,
    duration_s: float | None,
    deg: bool,
) -> str:
    """``moving  42%  1.3 s left  [0.1234, …] rad``: done, time left and the joints.

    Time left: from the plan when its duration is known (plan time still ahead, plus
    the lag the robot has built up), else extrapolated from the progress so far.
    """
    done = min(max(sample.progress, 0.0), 1.0)
    if duration_s is not None:
        left: float | None = max(0.0, duration_s - (sample.elapsed_s - sample.lag_s))
    elif done > 0.0:
        left = sample.elapsed_s * (1.0 - done) / done
    else:
        left = None
    width = 20
    bar = "#" * round(done * width)
    parts = [f"{label} [{bar:<{width}}] {done * 100:3.0f}%"]
    parts.append("time left ?" if left is None else f"{left:.1f} s left")
    if positions:
        unit = "deg" if deg else "rad"
        parts.append("[" + ", ".join(f"{to_user(p, deg):.3f}" for p in positions) + f"] {unit}")
    return "  ".join(parts)


@contextlib.contextmanager
def progress_bar(
    label: str,
    client: RobotClient | None = None,
    groups: Sequence[int] = (),
    *,
    duration_s: float | None = None,
    deg: bool = False,
    stream: IO[str] | None = None,
) -> Iterator[Callable[[FollowingSample], None]]:
    """A progress line on a terminal's stderr (done, time left, the joints from the
    feedback), fed by the following monitor's samples; nothing when stderr is not a
    terminal. Redrawn in place at most every :data:`PROGRESS_REDRAW_S`."""
    out = sys.stderr if stream is None else stream
    if not out.isatty():
        yield lambda _sample: None
        return
    columns = shutil.get_terminal_size().columns - 1
    last = [-math.inf]

    def progress(sample: FollowingSample) -> None:
        if sample.elapsed_s - last[0] < PROGRESS_REDRAW_S and sample.progress < 1.0:
            return
        last[0] = sample.elapsed_s
        here = (
            [] if client is None else [v for g in groups for v in client.state.positions(g) or ()]
        )
        line = progress_line(label, sample, here, duration_s=duration_s, deg=deg)
        out.write("\r\x1b[K" + line[:columns])
        out.flush()

    try:
        yield progress
    finally:
        out.write("\n")
        out.flush()


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


@dataclass(frozen=True, slots=True)
class MoveRequest:
    """What the user asked ``move`` for, as typed (checked by :meth:`check_usage`)."""

    joints: tuple[float, ...]
    name: str | None
    srdf: Path | None
    deg: bool
    speed_scale: float
    accel_scale: float
    group: tuple[str, ...]
    enable_first: bool
    as_json: bool
    as_pose: bool = False
    linear: bool = False
    relative: tuple[str, ...] = ()
    frame: str = "base"
    tcp_speed_mm_s: float = 250.0
    tool: int | None = None
    force: bool = False
    avoid: bool = False

    @property
    def cartesian(self) -> bool:
        return self.as_pose or bool(self.relative)

    def check_usage(self) -> None:
        """One target, given in a way that fits it (usage errors, exit 2)."""
        if self.linear and not self.as_pose:
            raise click.UsageError(
                "--linear goes with --pose (--relative moves are always straight)"
            )
        if self.as_pose and (self.relative or self.name is not None):
            raise click.UsageError("give one target: --pose, --relative or --named")
        if self.relative and self.joints:
            raise click.UsageError("--relative takes no positional values")
        if not self.cartesian and (self.name is None) == (not self.joints):
            raise click.UsageError("give either joint values J1 ... Jn or --named NAME")
        if self.srdf is not None and self.name is None:
            raise click.UsageError("--srdf goes with --named")
        if self.avoid and (self.linear or self.relative):
            raise click.UsageError(
                "--avoid plans a joint move around the obstacles (J1 ... Jn, --named or "
                "--pose without --linear); a straight line (--linear, --relative) cannot "
                "go around them"
            )


@dataclass(frozen=True, slots=True)
class MoveGoal:
    """The checked target of a move: its groups, their models, and the joint goal (a
    Cartesian move's goal is planned by the client: ``goal`` is empty)."""

    groups: tuple[int, ...]
    models: list[GroupModel]
    goal: tuple[float, ...]
    pose: tuple[float, ...] | None = None
    relative: tuple[float, ...] | None = None


def _named_groups(
    client: RobotClient, name: str, srdf: Path | None, given: tuple[int, ...]
) -> tuple[tuple[int, ...], tuple[float, ...]]:
    """The groups a named pose moves and its goal: the groups given with --group, else
    every group of the robot the pose sets (the built-in home sets them all)."""
    if given:
        return given, tuple(v for g in given for v in client.named_pose(name, srdf=srdf, group=g))
    groups: list[int] = []
    goal: list[float] = []
    first_error: NamedPoseError | None = None
    for index in range(len(client.robot.groups)):
        try:
            values = client.named_pose(name, srdf=srdf, group=index)
        except NamedPoseError as exc:
            first_error = first_error or exc
            continue
        groups.append(index)
        goal.extend(values)
    if not groups:
        assert first_error is not None  # noqa: S101 - a robot has at least one group
        raise first_error
    return tuple(groups), tuple(goal)


def resolve_goal(target: Target, req: MoveRequest) -> MoveGoal:
    """The goal checked against the robot model before anything is sent."""
    client = target.client()
    given = tuple(client.group_index(g) for g in req.group)
    if len(set(given)) != len(given):
        raise InputError("a --group is given twice: give each group once")
    if req.cartesian:
        if len(given) > 1:
            raise InputError("a Cartesian move (--pose, --relative) takes one --group")
        groups = given or (0,)
        rel = parse_relative(req.relative, req.deg) if req.relative else None
        pose = pose_from_args(req.joints, req.deg) if req.as_pose else None
        return MoveGoal(groups, [client.robot.groups[groups[0]]], (), pose, rel)
    if req.name is not None:
        groups, goal = _named_groups(client, req.name, req.srdf, given)
    else:
        groups = given or (0,)
        goal = _goal_from_values(req.joints, [client.robot.groups[g] for g in groups], req.deg)
    return MoveGoal(groups, [client.robot.groups[g] for g in groups], goal)


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


def _need_obstacles(cell: Path | CellModels | None) -> None:
    """``--avoid`` plans around the obstacles of the --config cell: without them it
    would silently plan a plain move (usage error, exit 2)."""
    models = None
    if cell is not None:
        models = cell if isinstance(cell, CellModels) else load_cell_models(cell)
    if models is None or not models.workspace.obstacles:
        raise click.UsageError(
            "--avoid needs --config CELL.toml whose [workspace] has obstacles: the cell "
            "file names them (the controller cannot report them)"
        )


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
        _echo_json(_move_data(result) | {"groups": names})
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
    target = _target(kwargs)
    req = MoveRequest(**kwargs)
    req.check_usage()
    try:
        if req.avoid:
            _need_obstacles(target.cell)
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


def _on_io_port(
    kwargs: dict[str, Any], call: Callable[[RobotClient], Coroutine[Any, Any, _T]]
) -> _T:
    """Run one request that needs only the IO port (MotoROS allows one IO client)."""
    target = _target(kwargs)

    async def work() -> _T:
        async with connected(target, motion=False, state=False, io=True) as client:
            return await call(client)

    return run(target, work)


def _say_value(as_json: bool, key: str, number: int, value: int, text: str) -> None:
    """``{key: number, "value": value}`` with --json, else ``text``."""
    if as_json:
        _echo_json({key: number, "value": value})
    else:
        click.echo(text)


_group_flag = click.option(
    "--group", "as_group", is_flag=True, help="ADDRESS is a group (byte) address."
)
_address_json = click.option(
    "--json", "as_json", is_flag=True, help='Print {"address": A, "value": V}.'
)
_number_json = click.option(
    "--json", "as_json", is_flag=True, help='Print {"number": N, "value": V}.'
)
"""The options the read and write commands of ``io`` and ``mreg`` share."""


@io.command("read", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("address", type=click.IntRange(0))
@_group_flag
@_address_json
def io_read(address: int, as_group: bool, as_json: bool, **kwargs: Any) -> None:
    """Read the IO bit (or group) at ADDRESS."""
    read = RobotClient.read_io_group if as_group else RobotClient.read_io_bit
    value = _on_io_port(kwargs, lambda client: read(client, address))
    _say_value(as_json, "address", address, value, str(value))


@io.command("write", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("address", type=click.IntRange(0))
@click.argument("value", type=click.IntRange(0))
@_group_flag
@_address_json
def io_write(address: int, value: int, as_group: bool, as_json: bool, **kwargs: Any) -> None:
    """Write VALUE (0/1, or 0..255 with --group) to the IO bit (or group) at ADDRESS."""
    write = RobotClient.write_io_group if as_group else RobotClient.write_io_bit
    _on_io_port(kwargs, lambda client: write(client, address, value))
    _say_value(as_json, "address", address, value, f"{address} = {value}")


@click.group(epilog=EXIT_CODES_HELP)
def mreg() -> None:
    """Read or write an M-register (read M000-M999, write M000-M559; 16 bits).

    Give the plain number (10 for M010), not 1000000 + n.
    """


@mreg.command("read", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0))
@_number_json
def mreg_read(number: int, as_json: bool, **kwargs: Any) -> None:
    """Read M-register NUMBER."""
    value = _on_io_port(kwargs, lambda client: client.read_mregister(number))
    _say_value(as_json, "number", number, value, str(value))


@mreg.command("write", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0))
@click.argument("value", type=click.IntRange(0))
@_number_json
def mreg_write(number: int, value: int, as_json: bool, **kwargs: Any) -> None:
    """Write VALUE (0..65535) to M-register NUMBER."""
    _on_io_port(kwargs, lambda client: client.write_mregister(number, value))
    _say_value(as_json, "number", number, value, f"M{number:03d} = {value}")


__all__ = ["disable", "enable", "io", "move", "mreg", "status", "stop", "tool"]
