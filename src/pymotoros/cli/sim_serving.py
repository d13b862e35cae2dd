"""What ``pymotoros sim`` does the same for one cell and for several (``cli/sim.py``,
``cli/sim_cells.py``): each cell's server config, the ready lines (an external
contract), SIGINT/SIGTERM, the recording, and running to the end with a clear error for
a port already in use.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import gc
import signal
import sys
from collections.abc import Callable, Coroutine, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from pymotoros.cli.ports_file import CellLabel, write_ports_file
from pymotoros.controller.cell import CellConfig
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig

if TYPE_CHECKING:
    from pymotoros.capture import SessionRecorder
    from pymotoros.controller.lint import ClientLint

__all__ = [
    "announce",
    "open_recorder",
    "ready_line",
    "serve",
    "simulator_config",
    "stop_on_signals",
]


def ready_line(motion: int | None, state: int | None, io: int | None, http: int | None) -> str:
    """The line ``pymotoros sim`` prints when it is ready (an external contract); a
    MotoROS port that is not listening yet (start-up checks) is printed as ``-``."""

    def show(port: int | None) -> str:
        return "-" if port is None else str(port)

    shown = f"motion={show(motion)} state={show(state)} io={show(io)}"
    return f"pymotoros sim ready {shown} http={http}"


def simulator_config(
    host: str,
    ports: Sequence[int],
    cell: CellConfig,
    token: str | None = None,
    allowed_hosts: Sequence[str] = (),
) -> SimulatorConfig:
    """Where one cell listens (``ports``: motion, state, io, http; 0: the OS chooses),
    in its controller's byte order (FS100 speaks big-endian, reference §1.1), the
    control API's bearer token (None: open, loopback only) and the names it answers to
    besides its own (``--allowed-host``)."""
    motion, state, io, http = ports
    return SimulatorConfig(
        host=host,
        motion_port=motion,
        state_port=state,
        io_port=io,
        http_port=http,
        byte_order=cell.controller.byte_order,
        token=token,
        allowed_hosts=tuple(allowed_hosts),
    )


def announce(
    apps: Sequence[SimulatorApp],
    labels: Sequence[CellLabel],
    ports_file: Path | None,
    *,
    several: bool,
) -> None:
    """Once every cell listens: write ``ports_file`` (each cell's bound ports, the first
    cell's at the top, and what each cell is), then print one ready line per cell, ended
    by ``cell=NAME`` when ``several`` (one write, so a reader never sees half of them)."""
    lines: list[str] = []
    entries: list[dict[str, Any]] = []
    for app, label in zip(apps, labels, strict=True):
        bound = app.ports
        line = ready_line(*app.listening_ports(), bound.http)
        lines.append(f"{line} cell={label.name}" if several else line)
        entries.append(label.entry((bound.motion, bound.state, bound.io, bound.http)))
    if ports_file is not None:  # the bound ports: they listen once MotoROS starts
        first = apps[0].ports
        write_ports_file(ports_file, first.motion, first.state, first.io, first.http, cells=entries)
    sys.stdout.write("".join(line + "\n" for line in lines))
    sys.stdout.flush()


@contextlib.contextmanager
def stop_on_signals(request_stop: Callable[[], None]) -> Iterator[None]:
    """Inside, SIGINT/SIGTERM call ``request_stop`` (one cell or several, cli/sim_cells.py)."""
    loop = asyncio.get_running_loop()
    handled: list[signal.Signals] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, request_stop)
            handled.append(sig)
    # Everything allocated so far (models, the web stack) is permanent: keep it out of the
    # collector's way so that a full collection cannot stall the 4 ms loop. Done before the
    # loop starts ticking.
    gc.collect()
    gc.freeze()
    try:
        yield
    finally:
        for sig in handled:
            loop.remove_signal_handler(sig)


def open_recorder(record_path: Path | None) -> SessionRecorder | None:
    """``--record``: one pcapng file for the twin's side of every connection of every cell
    (each cell's own ports tell its connections apart), given to each app's servers when
    the app is built."""
    if record_path is None:
        return None
    from pymotoros.capture import SessionRecorder

    try:
        recorder = SessionRecorder(record_path)
    except OSError as exc:
        raise click.ClickException(
            f"cannot write the recording {record_path}: {exc.strerror or exc}"
        ) from exc
    return recorder


def serve(
    main: Coroutine[Any, Any, None],
    *,
    host: str,
    ports_file: Path | None,
    recorder: SessionRecorder | None,
    port_hint: str,
    lint_report: tuple[Path, Sequence[tuple[str | None, ClientLint]]] | None = None,
) -> None:
    """Run ``main`` (one cell or several) to its end; remove the ports file, close the
    recording and write the lint report (``--lint-report``: file, each cell's lint)
    whatever happened, and turn a port already in use into an error that says what to do
    (``port_hint``)."""
    try:
        try:
            asyncio.run(main)
        finally:
            if ports_file is not None:
                ports_file.unlink(missing_ok=True)
            if recorder is not None:
                recorder.close()
            if lint_report is not None:
                from pymotoros.cli.lint import write_lint_report

                write_lint_report(*lint_report)
    except OSError as exc:  # e.g. a port already in use
        hint = (
            f"; another controller or sim holds the port: stop it, or {port_hint}"
            if exc.errno == errno.EADDRINUSE
            else ""
        )
        raise click.ClickException(f"cannot listen on {host}: {exc}{hint}") from exc
