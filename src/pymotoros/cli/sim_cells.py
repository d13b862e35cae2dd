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

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import click

from pymotoros.cli.ports_file import CellLabel
from pymotoros.cli.sim_serving import (
    announce,
    open_recorder,
    serve,
    simulator_config,
    stop_on_signals,
)
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import CellConfig, cell_from_file
from pymotoros.errors import ConfigError
from pymotoros.models.cell import PORT_KINDS, CellPorts, read_cell_file
from pymotoros.models.fidelity import Fidelity
from pymotoros.runtime.fleet import Fleet, FleetCell, cell_names, check_port_clashes
from pymotoros.runtime.tcp import ClientTasks

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
    lint_report: Path | None = None,
    allowed_hosts: Sequence[str] = (),
    fidelity: Fidelity | None = None,
) -> None:
    """Load every cell, check their ports, serve them until SIGINT/SIGTERM (``fidelity``:
    ``--fidelity``, over every cell's own ``[motoros] fidelity``)."""
    _refuse_single_cell_options(ctx, scenario_path)
    names = cell_names(paths)
    try:
        files = [read_cell_file(p) for p in paths]
        where = [f"cell {n} ({p})" for n, p in zip(names, paths, strict=True)]
        check_port_clashes([(w, f.ports) for w, f in zip(where, files, strict=True)])
        cells: list[FleetCell] = []
        labels: list[CellLabel] = []
        for name, path, cell_file in zip(names, paths, files, strict=True):
            cell = cell_from_file(cell_file)
            if fidelity is not None:
                cell = dataclasses.replace(cell, fidelity=fidelity)
            cells.append(_fleet_cell(name, cell, cell_file.ports, host, token, allowed_hosts))
            labels.append(CellLabel.of(name, cell, path))
        recorder = open_recorder(record_path)  # before the coroutine: it may refuse
        fleet = Fleet(cells, idle_batching=idle_batching, recorder=recorder)
    except ConfigError as exc:
        raise click.UsageError(str(exc)) from exc
    serve(
        run_fleet(fleet, labels, ports_file),
        host=host,
        ports_file=ports_file,
        recorder=recorder,
        port_hint="remove that port from the cell file's [ports] table (the OS then chooses one)",
        lint_report=None
        if lint_report is None
        else (lint_report, [(c.name, c.controller.lint) for c in cells]),
    )


def _fleet_cell(
    name: str,
    cell: CellConfig,
    ports: CellPorts,
    host: str,
    token: str | None,
    allowed_hosts: Sequence[str] = (),
) -> FleetCell:
    """One cell of the fleet: its controller, on its file's ports (else 0, the OS chooses),
    behind the one token (and the one list of names) every cell's control API shares."""
    listen = [ports.get(kind) or 0 for kind in PORT_KINDS]
    config = simulator_config(host, listen, cell, token, allowed_hosts)
    motion_clients = ClientTasks()  # the motion server keeps them: a scenario's drop_motion
    controller = VirtualController(cell, motion_link=motion_clients)
    return FleetCell(name, controller, config, motion_clients)


async def run_fleet(
    fleet: Fleet, labels: Sequence[CellLabel], ports_file: Path | None = None
) -> None:
    """Serve until SIGINT/SIGTERM; once every cell listens, print one ready line per
    cell (and write ``ports_file``: every cell, the first one's ports at the top)."""
    with stop_on_signals(fleet.request_stop):
        async with fleet:
            announce(fleet.apps, labels, ports_file, several=True)
            await fleet.wait_stopped()
