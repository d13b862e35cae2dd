"""``pymotoros sim --config a.toml --config b.toml ...``: several cells in one process.

Each cell listens on its own ports and has its own control API; one interpolation clock
ticks every cell (``runtime/fleet.py``). Once every cell listens, one ready line per cell,
in the order of the ``--config`` flags, the single-cell line extended with the cell's
name (the file's stem)::

    pymotoros sim ready motion=41871 state=40111 io=35667 http=44317 cell=hc10_yrc1000
    pymotoros sim ready motion=39719 state=43059 io=33421 http=37935 cell=fs100

Ports: a cell's ``[ports]`` table, else 0 (the OS chooses): with several cells no
default port is fixed, so two cells never ask for the same one; two cells (or two
servers) naming the same port in their files is a usage error naming both. The port
flags name one server's port, so with several cells only 0 is accepted (it changes
nothing); ``--controller``/``--robot`` (the cell files name the models) and
``--scenario`` (one cell's faults; load one into a cell with ``POST /api/scenario``)
are usage errors. ``--host`` applies to every cell.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from pymotoros.cli.sim import open_recorder, ready_line, serve, stop_on_signals, write_ports_file
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import load_cell
from pymotoros.errors import ConfigError
from pymotoros.runtime.app import SimulatorConfig
from pymotoros.runtime.fleet import (
    PORT_KINDS,
    Fleet,
    FleetCell,
    cell_names,
    check_port_clashes,
    read_cell_ports,
)

__all__ = ["run_cells", "run_fleet"]

_SOURCES = {
    click.core.ParameterSource.ENVIRONMENT: " (from the environment)",
    click.core.ParameterSource.DEFAULT_MAP: " (from the settings file)",
}


def _given(ctx: click.Context, name: str) -> bool:
    source = ctx.get_parameter_source(name)
    return source is not None and source is not click.core.ParameterSource.DEFAULT


def _refuse_single_cell_options(ctx: click.Context, scenario_path: Path | None) -> None:
    """Options that name one cell's settings make no sense for several: say so."""
    for option in ("controller_name", "robot_name"):
        if _given(ctx, option):
            flag = option.removesuffix("_name")
            raise click.UsageError(
                f"--{flag} cannot be used with several --config: each cell file names its "
                "own models ([controller] model, [robot] model)"
            )
    if scenario_path is not None:
        raise click.UsageError(
            "--scenario loads one cell's faults and cannot be used with several --config: "
            "run that cell on its own, or load the scenario into one cell through its "
            "control API (POST /api/scenario)"
        )
    for kind in PORT_KINDS:
        name = f"{kind}_port"
        port = ctx.params.get(name)
        if _given(ctx, name) and port != 0:
            source = ctx.get_parameter_source(name)
            origin = _SOURCES.get(source, "") if source is not None else ""
            raise click.UsageError(
                f"--{kind}-port {port}{origin} names one server's port and cannot be used "
                f"with several --config: set each cell's port in its cell file "
                f"([ports] {kind} = ...), or leave it out and the OS chooses"
            )


def run_cells(
    ctx: click.Context,
    paths: Sequence[Path],
    *,
    host: str,
    scenario_path: Path | None,
    ports_file: Path | None,
    record_path: Path | None = None,
    idle_batching: bool | None = None,
    token: str | None = None,
) -> None:
    """Load every cell, check their ports, serve them until SIGINT/SIGTERM."""
    _refuse_single_cell_options(ctx, scenario_path)
    names = cell_names(paths)
    try:
        asked = [read_cell_ports(p) for p in paths]
        where = [f"cell {n} ({p})" for n, p in zip(names, paths, strict=True)]
        check_port_clashes(list(zip(where, asked, strict=True)))
        cells = []
        titles = []
        for name, path, ports in zip(names, paths, asked, strict=True):
            cell = load_cell(path)
            config = SimulatorConfig(
                host=host,
                motion_port=ports.motion or 0,
                state_port=ports.state or 0,
                io_port=ports.io or 0,
                http_port=ports.http or 0,
                byte_order=cell.controller.byte_order,  # FS100 speaks big-endian
                token=token,  # one token for every cell's control API
            )
            cells.append(FleetCell(name, VirtualController(cell), config))
            titles.append(cell.name)
        fleet = Fleet(cells, idle_batching=idle_batching)
    except ConfigError as exc:
        raise click.UsageError(str(exc)) from exc
    recorder = open_recorder(record_path, fleet.apps)  # before the coroutine: it may refuse
    serve(
        run_fleet(fleet, paths, titles, ports_file),
        host=host,
        ports_file=ports_file,
        recorder=recorder,
        port_hint="remove that port from the cell file's [ports] table (the OS then chooses one)",
    )


async def run_fleet(
    fleet: Fleet,
    paths: Sequence[Path],
    titles: Sequence[str],
    ports_file: Path | None = None,
) -> None:
    """Serve until SIGINT/SIGTERM; once every cell listens, print one ready line per
    cell (and write ``ports_file``: the first cell's ports at the top, for the readers of
    a single cell's file, and every cell under ``cells``)."""
    with stop_on_signals(fleet.request_stop):
        async with fleet:
            lines: list[str] = []
            entries: list[dict[str, Any]] = []
            for name, path, title, app in zip(fleet.names, paths, titles, fleet.apps, strict=True):
                bound = app.ports
                motion, state, io = app.listening_ports()
                lines.append(f"{ready_line(motion, state, io, bound.http)} cell={name}")
                entries.append(
                    {
                        "cell": name,
                        "name": title,
                        "config": str(path),
                        "motion": bound.motion,
                        "state": bound.state,
                        "io": bound.io,
                        "http": bound.http,
                    }
                )
            if ports_file is not None:  # the bound ports: they listen once MotoROS starts
                first = fleet.apps[0].ports
                write_ports_file(
                    ports_file, first.motion, first.state, first.io, first.http, cells=entries
                )
            sys.stdout.write("".join(line + "\n" for line in lines))
            sys.stdout.flush()
            await fleet.wait_stopped()
