"""Several cells in one process: one interpolation clock ticks every controller.

``pymotoros sim --config a.toml --config b.toml`` runs one :class:`SimulatorApp` per
cell (its own motion/state/IO servers and control API, on its own ports) around one
shared :class:`~pymotoros.runtime.ticker.Ticker` whose step ticks every controller once,
in the order the cells were given. So the cells stay in lockstep (after any number of
periods every controller has ticked the same number of times), one timer wakes the loop
250 times a second however many cells there are, and a fleet costs one process instead
of N (docs/fleet.md says when to prefer which).

What is shared is the event loop and the clock: a cell's client cannot stall another
cell any more than it could stall its own (every tick's work is bounded, issue 13), and
each cell's connections, queues and faults are its own. The loop statistics
(``/api/state``'s ``tick``) are the process's, the same on every cell's control API.

Ports: a cell file may say where its cell listens::

    [ports]        # read by `pymotoros sim` only; every key optional
    motion = 50240
    state = 50241
    io = 50242
    http = 8080

With several cells, a port the file does not set is 0 (the OS chooses), and two cells
(or two servers of one cell) asking for the same port is a configuration error naming
both, found before anything listens (see :func:`check_port_clashes`).
"""

from __future__ import annotations

import asyncio
import math
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final, Self

import numpy as np

from pymotoros.capture import SessionRecorder
from pymotoros.errors import ConfigError
from pymotoros.models.cell import PORT_KINDS, CellPorts, read_cell_file
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig
from pymotoros.runtime.clock import Clock, precise_clock
from pymotoros.runtime.served import Served
from pymotoros.runtime.target import SimulatedController
from pymotoros.runtime.tcp import ClientTasks
from pymotoros.runtime.ticker import LATENESS_WINDOW, LatenessStats, Ticker, TickStats

__all__ = [
    "PORT_KINDS",
    "CellPorts",
    "Fleet",
    "FleetCell",
    "cell_names",
    "check_port_clashes",
    "read_cell_ports",
    "short_name",
]

_NOT_IN_NAME: Final = re.compile(r"[^A-Za-z0-9._-]")
"""Characters a cell's name on the ready line may not hold (it is one ``key=value``
token of a space-separated line)."""


def read_cell_ports(path: Path) -> CellPorts:
    """The ``[ports]`` table of the cell file ``path`` (empty when it has none), read by
    the one cell-file reader (:func:`~pymotoros.models.cell.read_cell_file`): a mistake
    anywhere in the file's shared part raises ConfigError naming the file and the key."""
    return read_cell_file(path).ports


def short_name(text: str) -> str:
    """``text`` made one token of the ready line: anything but letters, digits, ``.``,
    ``_`` and ``-`` becomes ``_`` (``"hc10 on yrc1000"`` is ``hc10_on_yrc1000``)."""
    return _NOT_IN_NAME.sub("_", text) or "cell"


def cell_names(paths: Sequence[Path]) -> list[str]:
    """A short, unique name per cell file for the ready line and the ports file: the
    file's stem with anything but letters, digits, ``.``, ``_`` and ``-`` made ``_``;
    a name seen before gets ``-2``, ``-3`` ... in the order given."""
    names: list[str] = []
    for path in paths:
        base = short_name(path.stem)
        name, n = base, 1
        while name in names:
            n += 1
            name = f"{base}-{n}"
        names.append(name)
    return names


def check_port_clashes(asked: Sequence[tuple[str, CellPorts]]) -> None:
    """Refuse two servers asking for the same fixed port (0 never clashes): in one cell
    or in two, named ``(where, ports)`` by where they come from (e.g. the cell file)."""
    taken: dict[int, str] = {}
    for where, ports in asked:
        for kind in PORT_KINDS:
            port = ports.get(kind)
            if not port:
                continue
            here = f"{where} ports.{kind}"
            if port in taken:
                raise ConfigError(
                    f"port {port} is asked for twice: by {taken[port]} and by {here}; give "
                    "each server its own port, or leave it out (0: the OS chooses)"
                )
            taken[port] = here


@dataclass(frozen=True, slots=True)
class FleetCell:
    """One cell of a fleet: its name (ready line), its controller and where it listens."""

    name: str
    controller: SimulatedController
    config: SimulatorConfig
    motion_clients: ClientTasks | None = None
    """The motion connections the controller was built with as its motion link (a
    scenario's drop_motion closes them; None: the controller has none)."""


class _TickAll:
    """One step of the shared loop: every controller's tick, in the cells' order.

    It also keeps how long each step took (a ring of the latest
    :data:`~pymotoros.runtime.ticker.LATENESS_WINDOW` steps): the last cell's tick starts
    that much after the loop's deadline plus its lateness, which is what bounds how many
    cells one loop can hold (``bench/bench_cells.py``).
    """

    def __init__(self, controllers: Sequence[SimulatedController]) -> None:
        self._ticks = tuple(c.tick for c in controllers)
        self._durations = np.zeros(LATENESS_WINDOW, dtype=np.float64)
        self._steps = 0

    def __call__(self) -> None:
        start = time.perf_counter()
        for tick in self._ticks:
            tick()
        self._durations[self._steps % len(self._durations)] = time.perf_counter() - start
        self._steps += 1

    def stats(self) -> LatenessStats:
        n = min(self._steps, len(self._durations))
        if not n:
            return LatenessStats(0.0, 0.0, 0.0)
        window = self._durations[:n]
        k50, k99 = max(1, math.ceil(0.5 * n)) - 1, max(1, math.ceil(0.99 * n)) - 1
        parted = np.partition(window, (k50, k99))
        return LatenessStats(
            p50=float(parted[k50]) * 1000.0,
            p99=float(parted[k99]) * 1000.0,
            max=float(window.max()) * 1000.0,
        )

    def reset(self) -> None:
        self._steps = 0


class Fleet(Served):
    """Several :class:`SimulatorApp` on one event loop, ticked by one :class:`Ticker`.

    ::

        async with Fleet([FleetCell("a", ctrl_a, cfg_a), FleetCell("b", ctrl_b, cfg_b)]) as f:
            print(f.apps[1].ports.motion)
            await f.wait_stopped()   # until request_stop() (a signal) or a crash

    Start-up is all or nothing: the cells start in order (each binds its ports at
    once), and if one cannot (a port in use) the started ones are stopped and the error
    is raised, naming the cell. The shared ticker starts once every cell listens. A
    crash of any cell or of a tick stops every cell, and :meth:`wait_stopped` re-raises
    it, as one :class:`SimulatorApp` does.
    """

    _what = "fleet"

    def __init__(
        self,
        cells: Sequence[FleetCell],
        *,
        clock: Clock | None = None,
        idle_batching: bool | None = None,
        recorder: SessionRecorder | None = None,
    ) -> None:
        """``recorder``: records every connection of every cell (``pymotoros sim --record``)."""
        super().__init__()
        if not cells:
            raise ValueError("a fleet needs at least one cell")
        names = [c.name for c in cells]
        if len(set(names)) != len(names):
            raise ValueError(f"cell names must be unique, got {names}")
        periods = {c.controller.period_ms for c in cells}
        if len(periods) != 1:
            shown = ", ".join(f"{c.name} {c.controller.period_ms} ms" for c in cells)
            raise ConfigError(
                f"cells with different interpolation periods cannot share one clock ({shown});"
                " run them in separate processes"
            )
        self.cells = tuple(cells)
        self.names = tuple(names)
        period_s = periods.pop() / 1000.0
        self._step = _TickAll([c.controller for c in cells])
        # Idle batching as for one cell (runtime/ticker.py), but only while nobody
        # observes ANY cell: the cells share the ticker, so they batch together.
        batching = clock is None if idle_batching is None else idle_batching
        self.ticker = Ticker(
            self._step,
            period_s,
            clock or precise_clock(),
            may_batch=self._nobody_observes if batching else None,
        )
        self.apps = tuple(
            SimulatorApp(
                c.controller,
                c.config,
                clock=clock,
                ticker=self.ticker,
                idle_batching=batching,
                motion_clients=c.motion_clients,
                recorder=recorder,
                metrics_cell=c.name,  # GET /metrics labels each family with its cell
            )
            for c in cells
        )
        self._started = False

    def _nobody_observes(self) -> bool:
        return all(app.observers.may_batch() for app in self.apps)

    def tick_stats(self) -> TickStats:
        return self.ticker.stats()

    def step_stats(self) -> LatenessStats:
        """How long one step (every cell's tick) took, milliseconds: the last cell's tick
        is that much later than the loop's lateness (:meth:`tick_stats`) says."""
        return self._step.stats()

    def reset_stats(self) -> None:
        """Forget the loop's lateness, overruns and step durations (e.g. after a warm-up)."""
        self.ticker.reset_stats()
        self._step.reset()

    async def __aenter__(self) -> Self:
        if self._started:
            raise RuntimeError("this Fleet has already served; create a new one")
        self._started = True
        started: list[SimulatorApp] = []
        try:
            for cell, app in zip(self.cells, self.apps, strict=True):
                try:
                    await app.__aenter__()
                except OSError as exc:  # a port in use: say which cell
                    raise OSError(exc.errno, f"cell {cell.name}: {exc.strerror or exc}") from exc
                started.append(app)
        except BaseException:
            await _stop_all(started)
            raise
        ticking = asyncio.create_task(self.ticker.run(), name="interpolation")
        self._task = asyncio.create_task(self._supervise(ticking), name="fleet")
        return self

    async def _supervise(self, ticking: asyncio.Task[None]) -> None:
        """Run until a stop is asked or anything ends (a crash); then stop every cell
        first (their clients see an orderly shutdown), the shared loop last."""
        stopping = asyncio.create_task(self._stop.wait(), name="fleet-stop")
        serving = [
            asyncio.create_task(app.wait_stopped(), name=f"cell-{name}")
            for name, app in zip(self.names, self.apps, strict=True)
        ]
        try:
            await asyncio.wait({stopping, ticking, *serving}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            stopping.cancel()
            await _stop_all(self.apps)
            ticking.cancel()
            done = await asyncio.gather(ticking, *serving, return_exceptions=True)
        errors = [e for e in done if isinstance(e, Exception)]
        if errors:
            if len(errors) == 1:
                raise errors[0]
            raise ExceptionGroup("cells of the fleet failed", errors)


async def _stop_all(apps: Sequence[SimulatorApp]) -> None:
    """Stop the apps together. What an app's serving raised is not lost: its
    ``wait_stopped`` task (in :meth:`Fleet._supervise`) reports it."""
    await asyncio.gather(*(app.stop() for app in apps), return_exceptions=True)
