"""The ``pymotoros`` command: one click group, subcommands loaded on demand.

Each subcommand lives in its own module and is imported only when it runs, so
``pymotoros status`` does not pay for the simulator's web framework and
``pymotoros sim`` does not import the motion planner. This module is the only
place that configures logging.
"""

from __future__ import annotations

import importlib
import logging
from typing import Final

import click

from pymotoros.cli.settings import (
    ENV_PREFIX,
    check_section,
    load_settings,
    name_envvars,
    name_the_source,
    settings_path,
)
from pymotoros.errors import ConfigError
from pymotoros.log_tags import NOTE, STOP_REPORT

# name -> ("module:attribute" of a click.Command, one-line help for the listing)
_COMMANDS: Final[dict[str, tuple[str, str]]] = {
    "sim": ("pymotoros.cli.sim:sim", "Run the virtual controller (MotoROS on 50240/50241/50242)."),
    "interpolate": (
        "pymotoros.cli.interpolate:interpolate",
        "Turn a trajectory CSV into the pulse increments MotoROS would queue.",
    ),
    "status": ("pymotoros.cli.status:status", "Show the robot's state."),
    "enable": ("pymotoros.cli.motion_commands:enable", "Enter trajectory mode (START_TRAJ_MODE)."),
    "disable": ("pymotoros.cli.motion_commands:disable", "Leave trajectory mode (STOP_TRAJ_MODE)."),
    "move": ("pymotoros.cli.move:move", "Move to joint positions or a named pose."),
    "stop": ("pymotoros.cli.motion_commands:stop", "Stop motion at once (STOP_MOTION)."),
    "io": ("pymotoros.cli.io_commands:io", "Read or write an IO bit or group."),
    "mreg": (
        "pymotoros.cli.register_outputs:mreg",
        "Read or write an M-register; decode a cell's S1CxG register outputs.",
    ),
    "tool": ("pymotoros.cli.motion_commands:tool", "Select the tool file a group moves with."),
    "urdf": ("pymotoros.cli.urdf:urdf", "Write a robot model's URDF (base_link to tool0)."),
    "reset": ("pymotoros.cli.motion_commands:reset", "Reset alarms and errors (RESET_ALARM)."),
    "servo": ("pymotoros.cli.motion_commands:servo", "Servo power on or off (START/STOP_SERVOS)."),
    "check": (
        "pymotoros.cli.trajectory:check",
        "Pre-flight a trajectory file: MotoROS's verdict and what it never checks.",
    ),
    "plan": ("pymotoros.cli.trajectory:plan", "Time waypoints within the robot's limits."),
    "run": ("pymotoros.cli.trajectory_run:run", "Stream exactly the points of a trajectory file."),
    "plot": ("pymotoros.cli.trajectory:plot", "Plot a trajectory per joint (PNG)."),
    "replay": (
        "pymotoros.cli.replay:replay",
        "Replay a recorded session against a fresh twin or a controller; print the diff.",
    ),
    "lint": (
        "pymotoros.cli.lint:lint",
        "Lint a recorded session: what the client does that a robot answers differently.",
    ),
}


_TYPED: Final = "pymotoros.typed_args"
"""``ctx.meta`` key: the arguments after the command's name, as typed."""


class _LazyGroup(click.Group):
    """A group whose subcommands are imported when first used."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(_COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        entry = _COMMANDS.get(cmd_name)
        if entry is None:
            return None
        target = entry[0]
        module_name, attr = target.split(":")
        command = getattr(importlib.import_module(module_name), attr)
        if not isinstance(command, click.Command):
            raise TypeError(f"{target} is not a click command")
        name_envvars(command, f"{ENV_PREFIX}_{cmd_name.upper()}")
        return command

    def resolve_command(
        self, ctx: click.Context, args: list[str]
    ) -> tuple[str | None, click.Command | None, list[str]]:
        ctx.meta[_TYPED] = list(args)  # what the user typed: see invoke
        return super().resolve_command(ctx, args)

    def invoke(self, ctx: click.Context) -> object:
        try:
            return super().invoke(ctx)
        except click.BadParameter as exc:  # from the environment? say which variable
            raise name_the_source(exc, ctx.meta.get(_TYPED, ())) from exc

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        # Listed from the table, so that --help imports no subcommand module.
        with formatter.section("Commands"):
            formatter.write_dl([(name, entry[1]) for name, entry in sorted(_COMMANDS.items())])


def configure_logging(verbose: int, quiet: bool) -> None:
    """Log to stderr; -v for INFO (one line per request and reply), -vv for DEBUG (the
    wire bytes too), -q for errors only."""
    if quiet:
        level = logging.ERROR
    elif verbose >= 2:
        level = logging.DEBUG
    elif verbose == 1:
        level = logging.INFO
    else:
        level = logging.WARNING
    handler = logging.StreamHandler()
    handler.setFormatter(_PersonFormatter("%(asctime)s %(levelname)-7s %(name)s: %(message)s"))
    handler.addFilter(_drop_stop_reports)
    logging.basicConfig(level=level, handlers=[handler], force=True)


class _PersonFormatter(logging.Formatter):
    """A note of the client (a move allowed with a remark) as a plain ``note: …`` line;
    every other record as a timestamped log line."""

    def format(self, record: logging.LogRecord) -> str:
        if getattr(record, NOTE, False):
            return f"note: {record.getMessage()}"
        return super().format(record)


def _drop_stop_reports(record: logging.LogRecord) -> bool:
    """The client's report of a move it stopped: the CLI says where the robot stopped in
    its error or its own line, so the log line would say it a second time. (A connection
    lost under a waiting request is logged at INFO by the client for the same reason.)"""
    return not getattr(record, STOP_REPORT, False)


@click.group(
    cls=_LazyGroup,
    context_settings={"help_option_names": ["-h", "--help"], "auto_envvar_prefix": ENV_PREFIX},
)
# package_name: the version is looked up when --version is given, not at every start
# (importlib.metadata costs ~15 ms of start-up; issue 13).
@click.version_option(package_name="pymotoros", prog_name="pymotoros")
@click.option(
    "-v", "--verbose", count=True, help="More log output (-v requests and replies, -vv debug)."
)
@click.option("-q", "--quiet", is_flag=True, help="Only log errors.")
@click.pass_context
def cli(ctx: click.Context, verbose: int, quiet: bool) -> None:
    """A virtual Yaskawa Motoman controller running MotoROS, and a client for real robots.

    \b
    Options come from, highest first: the command line, PYMOTOROS_* environment
    variables (PYMOTOROS_HOST, PYMOTOROS_PORTS_FILE …, PYMOTOROS_MOVE_SPEED_SCALE …),
    a settings file (PYMOTOROS_SETTINGS, ./pymotoros.toml or
    ~/.config/pymotoros/config.toml), then the defaults. See docs/client.md.
    """
    configure_logging(verbose, quiet)
    try:
        path = settings_path()
        if path is not None:
            ctx.default_map = load_settings(path, _COMMANDS)
    except ConfigError as exc:
        raise click.UsageError(str(exc)) from None
    if ctx.invoked_subcommand is not None and ctx.default_map:
        command = ctx.command
        if isinstance(command, click.Group):
            sub = command.get_command(ctx, ctx.invoked_subcommand)
            if sub is not None:
                check_section(ctx, sub)


def main() -> None:
    """Console-script entry point."""
    cli()
