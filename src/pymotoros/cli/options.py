"""The options several ``pymotoros`` commands share, declared once with one help text.

Why one module: the same flag (``--robot``, ``--speed-scale``, ``-o`` …) was written
out in each command and the copies drifted (different help, different checks). Each
function here is a decorator for one option (or one group of options, as the
connection options); a command states only what differs, such as the Python name
of the parameter or a default that is "the file's".

It also holds how bad input is told: :class:`BadInput` (one line, exit code 2, no
usage banner), and the parameter types for files read (:class:`InputFile`) and
written (:class:`OutputFile`), which refuse a missing file or a missing directory
before the command runs.
"""

from __future__ import annotations

import difflib
import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, TypeAlias, TypeVar

import click
from click.shell_completion import CompletionItem

from pymotoros.cli.settings import cell_option, envvar
from pymotoros.errors import PymotorosError
from pymotoros.models import DEFAULT_CONTROLLER, DEFAULT_ROBOT, ROBOTS, ControllerType
from pymotoros.protocol.constants import TCP_PORT_IO, TCP_PORT_MOTION, TCP_PORT_STATE

_F = TypeVar("_F", bound=Callable[..., Any])

EXIT_USAGE: Final = 2
"""Bad arguments: click's own usage errors, an IO address out of range, an unknown pose."""
EXIT_CONNECTION: Final = 3
"""No connection, connection lost, or no answer in time."""

PORT: Final = click.IntRange(1, 65535)


class BadInput(PymotorosError, click.ClickException):  # noqa: N818 (a name the CLI uses)
    """A file or value that cannot be used, told in one line without a usage banner
    (``error: …`` is what the robot commands print; click prints ``Error: …``): exit 2.
    A :class:`~pymotoros.errors.PymotorosError` too, so that the one tree holds."""

    exit_code = EXIT_USAGE


# --------------------------------------------------------------------------- file types


if TYPE_CHECKING:
    _PathParam: TypeAlias = click.ParamType[Path]  # generic from click 8.2 on
else:
    _PathParam = click.ParamType  # click 8.1's is not subscriptable


class _FileParam(_PathParam):
    """A path a shell completes as a file name."""

    name = "file"

    def shell_complete(
        self, ctx: click.Context, param: click.Parameter, incomplete: str
    ) -> list[CompletionItem]:
        return [CompletionItem(incomplete, type="file")]


class InputFile(_FileParam):
    """A file the command reads: it must exist and be a readable file (one-line error)."""

    def __init__(self, what: str = "file") -> None:
        self.what = what

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Path:
        path = Path(value)
        hint = _param_hint(param)
        if not path.exists():
            raise BadInput(
                f"{hint}: {path}: no such file; give the path of an existing {self.what}"
            )
        if path.is_dir():
            raise BadInput(f"{hint}: {path} is a directory; give the path of a {self.what}")
        if not os.access(path, os.R_OK):
            raise BadInput(f"{hint}: {path}: permission denied; make it readable (chmod u+r)")
        return path


class OutputFile(_FileParam):
    """A file the command writes: its directory must exist (one-line error, checked before
    any work, so a long computation does not end in a traceback)."""

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Path:
        path = Path(value)
        hint = _param_hint(param)
        parent = path.parent if str(path.parent) else Path(".")
        if path.is_dir():
            raise BadInput(f"{hint}: {path} is a directory; give a file name in it")
        if not parent.is_dir():
            raise BadInput(
                f"{hint}: cannot write {path}: the directory {parent} does not exist; "
                f"create it first (mkdir -p {parent})"
            )
        if not os.access(parent, os.W_OK):
            raise BadInput(f"{hint}: cannot write {path}: the directory {parent} is not writable")
        return path


def _param_hint(param: click.Parameter | None) -> str:
    if param is None:
        return "file"
    if isinstance(param, click.Option):
        return max(param.opts, key=len)
    return param.human_readable_name


def number_list(
    value: str | None, count: int, *, hint: str, what: str, positive: bool = False
) -> list[float] | None:
    """``"1.5,-2,0"`` → floats: exactly ``count`` finite numbers (each > 0 with
    ``positive``); ``what`` says what they are in the error (``the file's joints, rad``)."""
    if value is None:
        return None
    parts = [p.strip() for p in value.split(",")]
    if len(parts) != count:
        raise click.BadParameter(
            f"needs {count} comma-separated values ({what}), got {len(parts)}", param_hint=hint
        )
    out = []
    for i, part in enumerate(parts, start=1):
        try:
            number = float(part)
        except ValueError:
            raise click.BadParameter(
                f"value {i} ({part!r}) is not a number", param_hint=hint
            ) from None
        if not math.isfinite(number) or (positive and number <= 0):
            kind = "a positive number" if positive else "finite"
            raise click.BadParameter(f"value {i} ({part!r}) must be {kind}", param_hint=hint)
        out.append(number)
    return out


# --------------------------------------------------------------------------- options


def _apply(func: _F, options: list[Callable[[_F], _F]]) -> _F:
    for option in reversed(options):
        func = option(func)
    return func


CONTROLLER_HELP: Final = (
    "Controller model: byte order (FS100 is big-endian), interpolation period and IO map."
)
ROBOT_HELP: Final = (
    f"Robot model: joint names, limits and kinematics ({', '.join(sorted(ROBOTS))})."
)
CONFIG_HELP: Final = (
    "Cell file (the sim's format) naming the controller and the groups (and the FSU "
    "limits); replaces --controller/--robot."
)


def controller_option(
    dest: str = "controller", *, unset: str | None = None, env: bool = False
) -> Callable[[_F], _F]:
    """``--controller``; ``unset``: no default value, the help says what is used instead."""
    return click.option(
        "--controller",
        dest,
        type=click.Choice([t.value for t in ControllerType], case_sensitive=False),
        default=DEFAULT_CONTROLLER.value if unset is None else None,
        show_default=unset is None,
        envvar=envvar("controller") if env else None,
        help=CONTROLLER_HELP + ("" if unset is None else f" [default: {unset}]"),
    )


def robot_option(
    dest: str = "robot", *, unset: str | None = None, env: bool = False, note: str = ""
) -> Callable[[_F], _F]:
    """``--robot``; ``unset``: no default value, the help says what is used instead."""
    return click.option(
        "--robot",
        dest,
        default=DEFAULT_ROBOT if unset is None else None,
        show_default=unset is None,
        envvar=envvar("robot") if env else None,
        help=ROBOT_HELP
        + (f" {note}" if note else "")
        + ("" if unset is None else f" [default: {unset}]"),
    )


def config_option(dest: str = "cell_path", *, env: bool = False) -> Callable[[_F], _F]:
    """``--config CELL.toml``: the cell's controller and groups instead of the models."""
    return click.option(
        "--config",
        dest,
        type=InputFile("cell file (TOML)"),
        default=None,
        envvar=envvar("config") if env else None,
        metavar="CELL.toml",
        help=CONFIG_HELP,
    )


def model_options(
    *, controller: str = "controller", robot: str = "robot", config: str = "cell_path"
) -> Callable[[_F], _F]:
    """--controller and --robot whose default is the trajectory file's, or --config."""

    def decorate(func: _F) -> _F:
        return _apply(
            func,
            [
                controller_option(controller, unset=f"the file's, else {DEFAULT_CONTROLLER.value}"),
                robot_option(robot, unset=f"the file's, else {DEFAULT_ROBOT}"),
                config_option(config),
            ],
        )

    return decorate


def _scale_option(flag: str, what: str) -> Callable[[_F], _F]:
    return click.option(
        flag,
        type=click.FloatRange(0.0, 1.0, min_open=True),
        default=1.0,
        show_default=True,
        help=f"Fraction of each joint's maximum {what}.",
    )


speed_scale_option = _scale_option("--speed-scale", "velocity (like MoveIt's velocity scaling)")
accel_scale_option = _scale_option("--accel-scale", "acceleration (and jerk)")


def scale_options(func: _F) -> _F:
    """--speed-scale and --accel-scale."""
    return speed_scale_option(accel_scale_option(func))


def deg_option(what: str) -> Callable[[_F], _F]:
    """``--deg``: ``what`` is in degrees (default radians); linear axes stay in metres."""
    return click.option(
        "--deg", is_flag=True, help=f"{what} in degrees (default radians; linear axes in m)."
    )


def json_option(what: str = "the result") -> Callable[[_F], _F]:
    return click.option("--json", "as_json", is_flag=True, help=f"Print {what} as JSON.")


def enable_option(func: _F) -> _F:
    """``--enable``: START_TRAJ_MODE before the motion (``move``, ``run``)."""
    return click.option(
        "--enable", "enable_first", is_flag=True, help="Enter trajectory mode first."
    )(func)


def output_option(what: str, *, required: bool = False) -> Callable[[_F], _F]:
    """``-o/--output``: its directory must exist (checked before any work)."""
    return click.option(
        "-o",
        "--output",
        type=OutputFile(),
        required=required,
        default=None,
        help=f"{what} (its directory must exist).",
    )


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


def port_options(*, env: bool, defaults: bool) -> Callable[[_F], _F]:
    """--motion-port, --state-port, --io-port. ``defaults``: MotoROS's fixed ports as
    defaults; else None (the ports file's, then MotoROS's)."""

    def one(kind: str, number: int) -> Callable[[_F], _F]:
        return click.option(
            f"--{kind}-port",
            type=PORT,
            default=number if defaults else None,
            show_default=defaults,
            envvar=envvar(f"{kind}_port") if env else None,
            help=f"MotoROS's {kind} port" + ("." if defaults else f" [default: {number}]."),
        )

    def decorate(func: _F) -> _F:
        return _apply(
            func,
            [one("motion", TCP_PORT_MOTION), one("state", TCP_PORT_STATE), one("io", TCP_PORT_IO)],
        )

    return decorate


def connection_options(func: _F) -> _F:
    """What every robot command needs to reach a controller and to report (each also
    from ``PYMOTOROS_<NAME>``). Ports left unset come from ``--ports-file``, else
    MotoROS's fixed ports."""
    return _apply(
        func,
        [
            click.option(
                "--host",
                default="127.0.0.1",
                show_default=True,
                envvar=envvar("host"),
                help="Controller address.",
            ),
            port_options(env=True, defaults=False),
            click.option(
                "--ports-file",
                type=click.Path(dir_okay=False, path_type=Path),
                default=None,
                envvar=envvar("ports_file"),
                help="JSON file written by `pymotoros sim --ports-file`: the ports of a "
                "port-0 twin.",
            ),
        ],
    )


def token_option(func: _F) -> _F:
    """``--token``: the bearer token of the twin's control API (``pymotoros sim
    --token``), for a command that reads it over HTTP; also ``PYMOTOROS_TOKEN`` and
    ``token`` in the settings file, as for ``sim`` itself."""
    return click.option(
        "--token",
        default=None,
        envvar=envvar("token"),
        metavar="TOKEN",
        help="The control API's token (pymotoros sim --token), sent as "
        "'Authorization: Bearer TOKEN' with --api and the alarm texts.",
    )(func)


def robot_options(func: _F) -> _F:
    """The options every robot command takes: connection, models, timeout, debug, record,
    and ``--cell`` (which cell of a ports file)."""
    return _apply(
        cell_option(func),
        [
            connection_options,
            controller_option(env=True),
            robot_option(env=True),
            config_option(env=True),
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
                "--debug",
                is_flag=True,
                envvar=envvar("debug"),
                help="Show a traceback on errors.",
            ),
            click.option(
                "--record",
                type=OutputFile(),
                default=None,
                envvar=envvar("record"),
                help="Record every frame sent and received to this pcapng file (Wireshark).",
            ),
        ],
    )


# --------------------------------------------------------------------------- numbers

_NEGATIVE_NUMBER: Final = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


class NumbersCommand(click.Command):
    """A command whose arguments are numbers that may be negative (``move -0.5 0 …``
    needs no ``--``), while a mistyped option is still told as an unknown option with
    the nearest real one ("No such option: --speed Did you mean --speed-scale?").

    Why not click's ``ignore_unknown_options`` alone: it hands every unknown option to
    the arguments, so ``--speed`` was reported as "not a valid float".
    """

    def __init__(
        self, name: str | None, context_settings: dict[str, Any] | None = None, **kwargs: Any
    ) -> None:
        settings = {**(context_settings or {}), "ignore_unknown_options": True}
        super().__init__(name, context_settings=settings, **kwargs)

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        refuse_unknown_options(self, ctx, args)
        return super().parse_args(ctx, args)


def _option_arities(command: click.Command, ctx: click.Context) -> dict[str, bool]:
    """Every option string of ``command`` -> whether it takes a value."""
    known: dict[str, bool] = dict.fromkeys(ctx.help_option_names, False)
    for param in command.get_params(ctx):
        if isinstance(param, click.Option):
            takes = not (param.is_flag or param.count)
            for opt in (*param.opts, *param.secondary_opts):
                known[opt] = takes
    return known


def refuse_unknown_options(command: click.Command, ctx: click.Context, args: list[str]) -> None:
    """Raise click's NoSuchOption for the first token that looks like an option, is
    not a negative number and is no option of ``command``."""
    known = _option_arities(command, ctx)
    words = iter(args)
    for word in words:
        if word == "--":
            return
        if word in known:
            if known[word]:
                next(words, None)  # its value, whatever it looks like
            continue
        if not word.startswith("-") or word == "-" or _NEGATIVE_NUMBER.match(word):
            continue
        name = word.split("=", 1)[0]
        if name in known or (len(name) > 2 and not name.startswith("--") and name[:2] in known):
            continue  # --opt=value, or -oVALUE
        raise click.NoSuchOption(
            name, possibilities=difflib.get_close_matches(name, list(known)), ctx=ctx
        )


__all__ = [
    "BadInput",
    "InputFile",
    "NumbersCommand",
    "OutputFile",
    "accel_scale_option",
    "config_option",
    "connection_options",
    "controller_option",
    "deg_option",
    "group_option",
    "json_option",
    "model_options",
    "number_list",
    "output_option",
    "port_options",
    "refuse_unknown_options",
    "robot_option",
    "robot_options",
    "scale_options",
    "speed_scale_option",
    "token_option",
]
