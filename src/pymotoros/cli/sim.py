"""``pymotoros sim``: run a virtual controller with MotoROS on the network.

Prints exactly one line on stdout once every listener is up::

    pymotoros sim ready motion=50240 state=50241 io=50242 http=8080

and runs until Ctrl-C or SIGTERM, which stop it cleanly with exit code 0. Logs go
to stderr (``pymotoros -v sim`` for more). With ``--config`` repeated, several cells
run in this process, one ready line each (``cli/sim_cells.py``); what both share is in
``cli/sim_serving.py``.
"""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Any

import click

from pymotoros.cli.options import controller_option, robot_option
from pymotoros.cli.ports_file import CellLabel
from pymotoros.cli.sim_serving import (
    announce,
    open_recorder,
    serve,
    simulator_config,
    stop_on_signals,
)
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import CellConfig, cell_from_file, default_cell
from pymotoros.errors import ConfigError
from pymotoros.models.cell import PORT_KINDS, CellFile, CellPorts, read_cell_file
from pymotoros.models.fidelity import Fidelity
from pymotoros.protocol.constants import TCP_PORT_IO, TCP_PORT_MOTION, TCP_PORT_STATE
from pymotoros.runtime.app import DEFAULT_HTTP_PORT, SimulatorApp
from pymotoros.runtime.fleet import cell_names, short_name
from pymotoros.runtime.tcp import ClientTasks

logger = logging.getLogger(__name__)

_PORT = click.IntRange(0, 65535)


async def run_simulator(
    app: SimulatorApp, ports_file: Path | None = None, label: CellLabel | None = None
) -> None:
    """Serve until SIGINT/SIGTERM; print the ready line (and write ``ports_file``, with
    what ``label`` says the cell is) once listening."""
    with stop_on_signals(app.request_stop):
        async with app:
            announce([app], [label or CellLabel("cell")], ports_file, several=False)
            await app.wait_stopped()


class RepeatableOption(click.Option):
    """``--config`` repeats on the command line, but from the environment or a settings
    file it stays one path, as it was before several cells (never split, not refused)."""

    def value_from_envvar(self, ctx: click.Context) -> Any:
        value = self.resolve_envvar_value(ctx)
        return None if value is None else (value,)

    def type_cast_value(self, ctx: click.Context, value: Any) -> Any:
        if isinstance(value, str | Path):
            value = (value,)
        return super().type_cast_value(ctx, value)


def _label(cell: CellConfig, config_file: Path | None) -> CellLabel:
    """The ports file's words for the one cell: named after its file, else its title."""
    name = cell_names([config_file])[0] if config_file is not None else short_name(cell.name)
    return CellLabel.of(name, cell, config_file)


def cell_file_ports(
    ctx: click.Context, path: Path | CellPorts, ports: tuple[int, int, int, int]
) -> tuple[int, int, int, int]:
    """The ports of one cell: a flag given (command line, environment, settings file)
    wins, else the cell file's ``[ports]`` (``path``: the file, or its table read), else
    the flag's default."""
    asked = read_cell_file(path).ports if isinstance(path, Path) else path
    chosen = []
    for kind, port in zip(PORT_KINDS, ports, strict=True):
        from_file = asked.get(kind)
        default = ctx.get_parameter_source(f"{kind}_port") is click.core.ParameterSource.DEFAULT
        chosen.append(from_file if default and from_file is not None else port)
    motion, state, io, http = chosen
    return motion, state, io, http


def _cell(
    ctx: click.Context, controller_name: str, robot_name: str, cell_file: CellFile | None
) -> CellConfig:
    if cell_file is None:
        return default_cell(controller_name, robot_name)
    for option in ("controller_name", "robot_name"):
        if ctx.get_parameter_source(option) is click.core.ParameterSource.COMMANDLINE:
            logger.warning(
                "--%s is ignored: the cell file %s names the models",
                option.removesuffix("_name"),
                cell_file.source,
            )
    return cell_from_file(cell_file)


@click.command()
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on.")
@click.option("--motion-port", type=_PORT, default=TCP_PORT_MOTION, show_default=True)
@click.option("--state-port", type=_PORT, default=TCP_PORT_STATE, show_default=True)
@click.option("--io-port", type=_PORT, default=TCP_PORT_IO, show_default=True)
@click.option(
    "--http-port",
    type=_PORT,
    default=DEFAULT_HTTP_PORT,
    show_default=True,
    help="Control API port.",
)
@controller_option("controller_name")
@robot_option("robot_name")
@click.option(
    "--config",
    "config_path",
    cls=RepeatableOption,
    multiple=True,
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    metavar="CELL.toml",
    help="Cell file (controller, robots, tools, boot state); replaces --controller/--robot. "
    "Repeat it to run several cells in this process, one clock for all (docs/sim.md).",
)
@click.option(
    "--scenario",
    "scenario_path",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    default=None,
    metavar="FILE.toml",
    help="Fault scenario: timed [[events]] (E-stop, PFL, FSU, alarms ...), see docs/sim.md.",
)
@click.option(
    "--ports-file",
    type=click.Path(dir_okay=False, writable=True, path_type=Path),
    default=None,
    help="Write the ports taken, and what each cell is, as JSON here once listening "
    "(removed on exit); robot commands read it with --ports-file (and --cell NAME).",
)
@click.option(
    "--record",
    "record_path",
    type=click.Path(dir_okay=False, writable=True, path_type=Path),
    default=None,
    metavar="FILE.pcapng",
    help="Record the twin's side of every MotoROS connection (any client: the ROS "
    "driver, a PLC) to a pcapng file for Wireshark, `pymotoros replay` and `plot`.",
)
@click.option(
    "--lint-report",
    "lint_report",
    type=click.Path(dir_okay=False, writable=True, path_type=Path),
    default=None,
    metavar="FILE.json",
    help="When the twin stops, write the client lint's findings (what clients did that a "
    "real controller answers differently, as GET /api/lint) to this JSON file.",
)
@click.option(
    "--realtime",
    is_flag=True,
    help="Ask Linux for real-time scheduling (SCHED_FIFO, low priority): steadier ticks "
    "on a loaded machine; needs CAP_SYS_NICE or ulimit -r, else a warning and normal "
    "scheduling.",
)
@click.option(
    "--no-idle-batching",
    "no_idle_batching",
    is_flag=True,
    help="Tick every 4 ms even while no client is connected (by default an unobserved "
    "twin runs its ticks in batches of 100 ms, caught up before anyone looks).",
)
@click.option(
    "--token",
    envvar="PYMOTOROS_TOKEN",
    default=None,
    metavar="TOKEN",
    help="Require 'Authorization: Bearer TOKEN' on every /api route, /metrics and the "
    "/ws/state feed (also PYMOTOROS_TOKEN); needed to serve the control API beyond "
    "loopback. The MotoROS ports stay open, as on a real controller.",
)
@click.option(
    "--insecure-http",
    is_flag=True,
    help="Serve the control API beyond loopback without a token (a warning is logged).",
)
@click.option(
    "--allowed-host",
    multiple=True,
    metavar="NAME",
    callback=lambda _ctx, _param, names: _allowed_hosts(names),
    help="A name the control API answers to besides its own (localhost, 127.0.0.1, "
    "[::1], --host; on 0.0.0.0 also the machine's name and any IP address); other Host "
    "headers are refused (DNS rebinding). Repeatable; .example.com (or *.example.com) "
    "allows every name under it, * any name.",
)
@click.option(
    "--fidelity",
    type=click.Choice([f.value for f in Fidelity]),
    default=None,
    help="exact: behave as MotoROS 1.9.12 where it is surprising (fragments answered 3001, "
    "queues resumed by the next motion connection, stale replies); safe: the twin's kinder "
    "behaviour (docs/fidelity.md). Default: the cell file's [motoros] fidelity, else exact.",
)
@click.pass_context
def sim(
    ctx: click.Context,
    host: str,
    motion_port: int,
    state_port: int,
    io_port: int,
    http_port: int,
    controller_name: str,
    robot_name: str,
    config_path: tuple[Path, ...],
    scenario_path: Path | None,
    ports_file: Path | None,
    record_path: Path | None = None,
    lint_report: Path | None = None,
    realtime: bool = False,
    no_idle_batching: bool = False,
    token: str | None = None,
    insecure_http: bool = False,
    allowed_host: tuple[str, ...] = (),
    fidelity: str | None = None,
) -> None:
    """Run the virtual controller (MotoROS on 50240/50241/50242, control API on --http-port).

    It runs in the foreground until Ctrl-C or SIGTERM: use a second terminal for the
    robot commands. Port 0 lets the OS choose; the ready line (and --ports-file) tells
    which ports were taken.
    """
    token = check_http_access(host, token, insecure_http)  # runtime/access.py
    if len(config_path) > 1:
        from pymotoros.cli.sim_cells import run_cells

        _request_realtime(realtime)
        run_cells(
            ctx,
            config_path,
            host=host,
            scenario_path=scenario_path,
            ports_file=ports_file,
            record_path=record_path,
            idle_batching=False if no_idle_batching else None,
            token=token,
            lint_report=lint_report,
            allowed_hosts=allowed_host,
            fidelity=None if fidelity is None else Fidelity(fidelity),
        )
        return
    config_file = config_path[0] if config_path else None
    ports = (motion_port, state_port, io_port, http_port)
    cell, controller, motion_clients, asked = _one_cell(
        ctx,
        (controller_name, robot_name),
        config_file,
        scenario_path,
        None if fidelity is None else Fidelity(fidelity),
    )
    ports = cell_file_ports(ctx, asked, ports)  # a [ports] table fills the flags not given
    _request_realtime(realtime)
    recorder = open_recorder(record_path)  # before the coroutine: it may refuse
    app = SimulatorApp(
        controller,
        simulator_config(host, ports, cell, token, allowed_host),
        idle_batching=False if no_idle_batching else None,
        motion_clients=motion_clients,
        recorder=recorder,
    )
    serve(
        run_simulator(app, ports_file, _label(cell, config_file)),
        host=host,
        ports_file=ports_file,
        recorder=recorder,
        port_hint="let the OS choose with --motion-port 0 --state-port 0 --io-port 0 "
        "--http-port 0 --ports-file FILE",
        lint_report=None if lint_report is None else (lint_report, [(None, controller.lint)]),
    )


def _one_cell(
    ctx: click.Context,
    models: tuple[str, str],
    config_file: Path | None,
    scenario_path: Path | None,
    fidelity: Fidelity | None = None,
) -> tuple[CellConfig, VirtualController, ClientTasks, CellPorts]:
    """The one cell's controller (``models``: --controller and --robot, when no file),
    with the scenario loaded, the motion connections it was built with as its motion
    link (the motion server keeps them: a scenario's drop_motion), and the ports its file
    asks for (none without a file); a mistake in a file is a usage error."""
    try:
        cell_file = read_cell_file(config_file) if config_file is not None else None
        cell = _cell(ctx, *models, cell_file)
        if fidelity is not None:  # --fidelity over the file's [motoros] fidelity
            cell = dataclasses.replace(cell, fidelity=fidelity)
        motion_clients = ClientTasks()
        controller = VirtualController(cell, motion_link=motion_clients)
        if scenario_path is not None:
            from pymotoros.controller.scenario import load_scenario

            controller.load_scenario(load_scenario(scenario_path))
    except ConfigError as exc:
        raise click.UsageError(str(exc)) from exc
    ports = cell_file.ports if cell_file is not None else CellPorts()
    return cell, controller, motion_clients, ports


def _request_realtime(realtime: bool) -> None:
    if realtime:
        from pymotoros.runtime.realtime import request_realtime

        request_realtime()  # a warning line if refused; the twin runs on either way


def _allowed_hosts(names: tuple[str, ...]) -> tuple[str, ...]:
    """The names as given, a usage error for one no Host could match (``twin-*``)."""
    from pymotoros.runtime.hosts import allowed_name

    for name in names:
        try:
            allowed_name(name)
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint="'--allowed-host'") from exc
    return names


def check_http_access(host: str, token: str | None, insecure: bool) -> str | None:
    """The token to serve with, trimmed of the whitespace around it; a usage error
    (exit 2) for a token with whitespace inside, a control API beyond loopback without
    one (unless ``--insecure-http``: then a warning) or with a weak one (too short, a
    placeholder)."""
    from pymotoros.runtime.access import clean_token, loopback_or_token, weak_token
    from pymotoros.runtime.tcp import is_loopback

    source = _token_source(token)
    try:
        token = clean_token(token, source=source)
    except ValueError as exc:
        raise click.UsageError(str(exc)) from exc
    if is_loopback(host):
        return token
    refusal = loopback_or_token(host, token, insecure)
    if refusal is None and token is not None:
        refusal = weak_token(token, host, source=source)
    if refusal is not None:
        raise click.UsageError(refusal)
    if token is None:
        logging.getLogger(__name__).warning(
            "--insecure-http: the control API on %s has no token; anybody who reaches it "
            "can E-stop, move and force IO",
            host,
        )
    return token


def _token_source(token: str | None) -> str:
    """Where the token came from, in the words of an error: the flag, the environment
    variable or the settings file."""
    ctx = click.get_current_context(silent=True)
    source = ctx.get_parameter_source("token") if ctx is not None and token else None
    if source is click.core.ParameterSource.ENVIRONMENT:
        return "PYMOTOROS_TOKEN"
    if source is click.core.ParameterSource.DEFAULT_MAP:
        return "token in the settings file"
    return "--token"
