"""``SimulatorApp``: one virtual controller on the network.

One ``asyncio.TaskGroup`` owns every task: the interpolation loop, the state
broadcaster, the three MotoROS servers' client handlers and the HTTP control API
(uvicorn, served inside the same event loop from a pre-bound socket, its signal
handlers disabled). If any of them crashes, the group cancels the rest and
:meth:`SimulatorApp.serve` re-raises, so a broken ticker never leaves servers half
alive.

Shutdown is ordered and idempotent: stop accepting (close every listener), close
the clients, stop the HTTP server, cancel the loops, release the sockets.

::

    async with SimulatorApp.for_cell(cell, SimulatorConfig(motion_port=0, ...)) as app:
        print(app.ports.motion)   # the port the OS chose
        ...

``SimulatorApp.for_cell`` builds the controller itself, with the motion port's client
set as its motion link (a scenario's ``drop_motion`` closes those connections);
``SimulatorApp(controller, ...)`` serves a controller built elsewhere, which reaches the
motion server only if it was built with that link (``motion_clients``).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
from collections.abc import Generator
from dataclasses import dataclass, field
from typing import Final, Self

import uvicorn

from pymotoros.capture import SessionRecorder
from pymotoros.controller.cell import CellConfig
from pymotoros.controller.controller import VirtualController
from pymotoros.errors import ConfigError
from pymotoros.models.cell import PORT_KINDS
from pymotoros.protocol.constants import (
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    TCP_PORT_STATE,
    ByteOrder,
)
from pymotoros.runtime.access import clean_token, install_access, weak_token
from pymotoros.runtime.clock import Clock, LoopClock, precise_clock
from pymotoros.runtime.hosts import HostGuard, own_names
from pymotoros.runtime.http_api import create_http_app
from pymotoros.runtime.io_server import IoServer
from pymotoros.runtime.metrics import install_metrics
from pymotoros.runtime.motion_server import MotionServer
from pymotoros.runtime.observers import Observers
from pymotoros.runtime.served import Served
from pymotoros.runtime.slow_requests import REQUEST_READ_TIMEOUT_S, bounded
from pymotoros.runtime.state_server import (
    STATE_MESSAGE_GAP_S,
    STATE_PERIOD_S,
    StateServer,
)
from pymotoros.runtime.target import SimulatedController
from pymotoros.runtime.tcp import (
    ClientTasks,
    ServiceWiring,
    bind_socket,
    bind_unlistened,
    is_loopback,
)
from pymotoros.runtime.ticker import Ticker, TickStats

__all__ = ["DEFAULT_HTTP_PORT", "BoundPorts", "SimulatorApp", "SimulatorConfig"]

logger = logging.getLogger(__name__)

DEFAULT_HTTP_PORT: Final = 8080
"""The control API's default port (``pymotoros sim --http-port``)."""

MOTOROS_PORTS: Final = 3
"""Motion, state and IO: the first three sockets, MotoROS's (the fourth is the control API)."""
STARTUP_POLL_TICKS: Final = 25
"""How often (ticks: 100 ms at 4 ms) the runtime looks whether MotoROS has started."""
HTTP_STOP_TIMEOUT_S: Final = 3.0
"""How long the HTTP server may take to finish its requests at shutdown."""


def _port_role(kind: str, port: int) -> str:
    """Which server a port is for, in the words of an error: "the MotoROS motion port
    50240" or "the control API (http) port 8080" (0: "a port the OS chooses")."""
    which = "the control API (http)" if kind == "http" else f"the MotoROS {kind}"
    return f"{which} port {port}" if port else f"{which} port (0: the OS chooses)"


@dataclass(frozen=True, slots=True)
class SimulatorConfig:
    """Where and how the simulator listens. Port 0 lets the OS choose; ``http_port=None``
    runs without the control API."""

    host: str = "127.0.0.1"
    motion_port: int = TCP_PORT_MOTION
    state_port: int = TCP_PORT_STATE
    io_port: int = TCP_PORT_IO
    http_port: int | None = DEFAULT_HTTP_PORT
    byte_order: ByteOrder = ByteOrder.LITTLE
    state_period: float = STATE_PERIOD_S
    state_message_gap: float = STATE_MESSAGE_GAP_S
    token: str | None = None
    """The control API's bearer token (``pymotoros sim --token``): None leaves it open.
    Whitespace around it is dropped; beyond loopback it must not be weak
    (runtime/access.py: :func:`~pymotoros.runtime.access.weak_token`)."""
    allowed_hosts: tuple[str, ...] = ()
    """Names besides its own the control API answers to in ``Host``
    (``pymotoros sim --allowed-host``; runtime/hosts.py)."""
    request_timeout_s: float = REQUEST_READ_TIMEOUT_S
    """Seconds a client has to send a whole HTTP request (runtime/slow_requests.py)."""

    def __post_init__(self) -> None:
        try:
            token = clean_token(self.token)
        except ValueError as exc:
            raise ConfigError(str(exc)) from exc
        object.__setattr__(self, "token", token)
        if token is not None and not is_loopback(self.host):
            weak = weak_token(token, self.host)
            if weak is not None:
                raise ConfigError(weak)


@dataclass(frozen=True, slots=True)
class BoundPorts:
    """The ports actually listened on (the OS's choice where 0 was asked)."""

    motion: int
    state: int
    io: int
    http: int | None = field(default=None)


class SimulatorApp(Served):
    """The servers, the interpolation loop and the control API around one controller."""

    _what = "simulator"

    def __init__(
        self,
        controller: SimulatedController,
        config: SimulatorConfig | None = None,
        *,
        clock: Clock | None = None,
        idle_batching: bool | None = None,
        ticker: Ticker | None = None,
        motion_clients: ClientTasks | None = None,
        recorder: SessionRecorder | None = None,
        metrics_cell: str | None = None,
    ) -> None:
        """``motion_clients``: the motion connections the controller was built with as its
        motion link (:meth:`for_cell` does both); ``recorder``: records every connection
        (``pymotoros sim --record``); ``metrics_cell``: the cell's name as a ``cell``
        label of ``GET /metrics`` (a process running several cells, runtime/fleet.py)."""
        super().__init__()
        self.controller = controller
        self.config = config or SimulatorConfig()
        self.metrics_cell = metrics_cell
        """The cell's name as a ``cell`` label of ``GET /metrics`` (None: one cell)."""
        self.clock: Clock = clock or LoopClock()
        # Real time: the interpolation loop sleeps on a precise timer (a timerfd in the
        # selector, or a timer thread; issue 13) instead of spinning the last
        # millisecond; the same time line, so the state stream and the ticker agree.
        tick_clock: Clock = clock or precise_clock()
        # Idle batching (issue 13): on by default in real time, off on a given clock
        # (virtual time steps tick by tick); idle_batching=False turns it off.
        self.idle_batching = clock is None if idle_batching is None else idle_batching
        self.observers = Observers(self._client_numbers, self._catch_up)
        # Several cells in one process share one ticker that ticks them all in turn
        # (runtime/fleet.py): its owner runs it (and batches only when every cell's
        # observers allow); this app only reads and waits on it.
        self._owns_ticker = ticker is None
        self.ticker = ticker or Ticker(
            controller.tick,
            controller.period_ms / 1000.0,
            tick_clock,
            may_batch=self.observers.may_batch if self.idle_batching else None,
        )
        order = self.config.byte_order
        # every server catches the ticker up on accept and limits its log flood in the
        # app's time
        wiring = ServiceWiring(catch_up=self._catch_up, log_clock=self.clock.now, recorder=recorder)
        motion_wiring = wiring.copy()
        if motion_clients is not None:  # the controller's motion link (for_cell)
            motion_wiring["clients"] = motion_clients
        self.motion = MotionServer(controller, order, **motion_wiring)
        self.state = StateServer(
            controller,
            order,
            self.clock,
            period=self.config.state_period,
            message_gap=self.config.state_message_gap,
            **wiring,
        )
        self.io = IoServer(controller, order, **wiring)
        self._ports: BoundPorts | None = None
        self._ready = asyncio.Event()
        self._http: _EmbeddedUvicorn | None = None
        self._http_task: asyncio.Task[None] | None = None
        self._loop_tasks: list[asyncio.Task[None]] = []
        self._started = False
        self._shutdown_done = False
        self._motoros_listening = False

    @classmethod
    def for_cell(
        cls,
        cell: CellConfig,
        config: SimulatorConfig | None = None,
        *,
        seed: int = 0,
        clock: Clock | None = None,
        idle_batching: bool | None = None,
        ticker: Ticker | None = None,
        recorder: SessionRecorder | None = None,
        metrics_cell: str | None = None,
    ) -> SimulatorApp:
        """A :class:`~pymotoros.controller.VirtualController` of ``cell`` served by a new
        app: the controller is built with the motion server's client set as its motion
        link, so a scenario's ``drop_motion`` closes the motion connections."""
        clients = ClientTasks()
        return cls(
            VirtualController(cell, seed=seed, motion_link=clients),
            config,
            clock=clock,
            idle_batching=idle_batching,
            ticker=ticker,
            motion_clients=clients,
            recorder=recorder,
            metrics_cell=metrics_cell,
        )

    # ----------------------------------------------------------- public

    @property
    def ports(self) -> BoundPorts:
        if self._ports is None:
            raise RuntimeError("the simulator is not listening yet")
        return self._ports

    def tick_stats(self) -> TickStats:
        return self.ticker.stats()

    @property
    def ready(self) -> asyncio.Event:
        """Set once every listener is up."""
        return self._ready

    async def serve(self) -> None:
        """Listen and run until :meth:`request_stop` or cancellation; then shut down in order.

        An application serves once; build a new one to serve again.
        """
        if self._started:
            raise RuntimeError("this SimulatorApp has already served; create a new one")
        self._started = True
        cfg = self.config
        if not is_loopback(cfg.host) and not cfg.token:
            logger.warning(
                "listening on %s: the simulator is reachable from the network and has no "
                "authentication (the control API and the web pendant at / can press E-stop, "
                "move the robot and force IO)",
                cfg.host,
            )
        elif not is_loopback(cfg.host):
            logger.info(
                "listening on %s: the control API needs its token; the MotoROS ports are "
                "open to anyone who reaches them, as on a real controller",
                cfg.host,
            )
        # Bind everything first: a port in use is a plain OSError, before any task starts.
        socks = self._bind_all()
        try:
            async with asyncio.TaskGroup() as tg:
                try:
                    motion, state, io = (int(s.getsockname()[1]) for s in socks[:3])
                    if self._motoros_started():
                        await self._start_motoros(tg, socks)
                    http = await self._start_http(tg, socks[3]) if len(socks) > 3 else None
                    self._ports = BoundPorts(motion, state, io, http)
                    self._loop_tasks = [
                        *self._own_ticker_task(tg),
                        tg.create_task(self.state.broadcast(), name="state-broadcast"),
                    ]
                    if not self._motoros_listening:
                        self._loop_tasks.append(
                            tg.create_task(
                                self._start_motoros_when_ready(tg, socks), name="motoros-startup"
                            )
                        )
                    logger.info(
                        "simulator ready: motion %d, state %d, io %d, http %s (period %d ms, %s)",
                        motion,
                        state,
                        io,
                        http,
                        self.controller.period_ms,
                        "big-endian" if cfg.byte_order is ByteOrder.BIG else "little-endian",
                    )
                    self._ready.set()
                    await self._stop.wait()
                finally:
                    await self._shutdown()
        finally:
            for sock in socks:  # already closed by their servers, unless start-up failed
                sock.close()

    @property
    def motoros_listening(self) -> bool:
        """MotoROS's servers listen (False while its start-up checks hold it back)."""
        return self._motoros_listening

    def listening_ports(self) -> tuple[int | None, int | None, int | None]:
        """(motion, state, io) ports that accept connections; None while not listening."""
        if self._ports is None or not self._motoros_listening:
            return (None, None, None)
        return (self._ports.motion, self._ports.state, self._ports.io)

    def catch_up(self) -> int:
        """Bring the controller up to date (idle batching) before reading it directly;
        the servers and the control API do this themselves. Returns the ticks run."""
        return self.ticker.catch_up()

    def _catch_up(self) -> None:
        self.ticker.catch_up()

    def _client_numbers(self) -> tuple[int, int, int]:
        return (self.motion.clients, self.state.clients, self.io.clients)

    def client_counts(self) -> dict[str, int]:
        """Clients connected on each MotoROS port (the web pendant shows them)."""
        return {"motion": self.motion.clients, "state": self.state.clients, "io": self.io.clients}

    def _own_ticker_task(self, tg: asyncio.TaskGroup) -> list[asyncio.Task[None]]:
        """The interpolation loop's task, unless a shared ticker is run by its owner."""
        if not self._owns_ticker:
            return []
        return [tg.create_task(self.ticker.run(), name="interpolation")]

    def _motoros_started(self) -> bool:
        started = getattr(self.controller, "motoros_started", True)
        return bool(started)

    async def _start_motoros(self, tg: asyncio.TaskGroup, socks: list[socket.socket]) -> None:
        await self.motion.start(tg, socks[0])
        await self.state.start(tg, socks[1])
        await self.io.start(tg, socks[2])
        self._motoros_listening = True

    async def _start_motoros_when_ready(
        self, tg: asyncio.TaskGroup, socks: list[socket.socket]
    ) -> None:
        """MotoROS's servers start once its start-up checks pass (never after a fatal one)."""
        logger.warning(
            "MotoROS is not started yet (%s): its ports refuse connections",
            getattr(self.controller, "motoros_phase", "start-up checks"),
        )
        while not self._motoros_started():
            await self.ticker.wait_ticks(STARTUP_POLL_TICKS)
        await self._start_motoros(tg, socks)
        logger.info("MotoROS started: motion, state and IO ports listening")

    def _bind_all(self) -> list[socket.socket]:
        cfg = self.config
        ports = [cfg.motion_port, cfg.state_port, cfg.io_port]
        if cfg.http_port is not None:
            ports.append(cfg.http_port)
        socks: list[socket.socket] = []
        try:
            for i, (kind, port) in enumerate(zip(PORT_KINDS, ports, strict=False)):
                # MotoROS's ports are bound now (a port in use fails at once) but listen
                # only when its servers start
                bind = bind_unlistened if i < MOTOROS_PORTS else bind_socket
                try:
                    socks.append(bind(cfg.host, port))
                except OSError as exc:  # say which server's port: e.g. "the motion port 50240"
                    raise OSError(exc.errno, f"{_port_role(kind, port)}: {exc.strerror}") from exc
        except BaseException:
            for sock in socks:
                sock.close()
            raise
        return socks

    async def __aenter__(self) -> Self:
        self._task = asyncio.create_task(self.serve(), name="simulator")
        ready = asyncio.create_task(self._ready.wait(), name="simulator-ready")
        try:
            await asyncio.wait({self._task, ready}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            ready.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await ready
        if self._task.done():
            self._task.result()  # raises what stopped it
            raise RuntimeError("the simulator stopped before it was ready")
        return self

    # ----------------------------------------------------------- internals

    async def _start_http(self, tg: asyncio.TaskGroup, sock: socket.socket) -> int:
        bound = int(sock.getsockname()[1])
        app = create_http_app(
            self.controller,
            self.tick_stats,
            self.ticker.reset_stats,
            ports=self.listening_ports,
            clients=self.client_counts,
            after_ticks=self.ticker.wait_ticks,
            observers=self.observers if self.idle_batching else None,
        )
        install_metrics(app, self)  # GET /metrics (runtime/metrics.py)
        install_access(app, self.config.token, ready=lambda: self.motoros_listening)
        # outermost: a request for another name (DNS rebinding) is refused before anything
        app.add_middleware(HostGuard, names=own_names(self.config.host, self.config.allowed_hosts))
        config = uvicorn.Config(
            app,
            # h11 with a deadline on each request: half-sent requests are closed
            http=bounded(self.config.request_timeout_s),
            log_level="warning",
            lifespan="off",
            access_log=False,
            timeout_graceful_shutdown=1,
            # the pendant's feed: compressing each document for each tab would cost the
            # loop CPU for nothing on a local link
            ws_per_message_deflate=False,
        )
        config.load()  # the slow part of uvicorn's start-up, done before the loop starts ticking
        server = _EmbeddedUvicorn(config)
        self._http = server
        self._http_task = tg.create_task(_serve_http(server, sock), name="http-api")
        logger.info("control API on http://%s:%d/api/state (docs: /docs)", self.config.host, bound)
        return bound

    async def _shutdown(self) -> None:
        if self._shutdown_done:
            return
        self._shutdown_done = True
        self._ready.clear()
        logger.info("simulator stopping")
        servers = (self.motion, self.state, self.io)
        # 1. stop accepting
        for server in servers:
            server.stop_accepting()
        if self._http is not None:
            self._http.should_exit = True
        # 2. close the clients
        for server in servers:
            await server.close_clients()
        # 3. stop the HTTP server, cancel the loops and wait for every task
        if self._http_task is not None:
            with contextlib.suppress(TimeoutError, asyncio.CancelledError):
                async with asyncio.timeout(HTTP_STOP_TIMEOUT_S):
                    await asyncio.shield(self._http_task)
        for task in self._loop_tasks:
            task.cancel()
        # 4. release the listening sockets
        for server in servers:
            await server.wait_closed()
        logger.info("simulator stopped")


async def _serve_http(server: _EmbeddedUvicorn, sock: socket.socket) -> None:
    try:
        await server.serve(sockets=[sock])
    finally:
        sock.close()


class _EmbeddedUvicorn(uvicorn.Server):
    """uvicorn without its signal handlers: the application owns SIGINT/SIGTERM."""

    @contextlib.contextmanager
    def capture_signals(self) -> Generator[None, None, None]:
        yield

    def install_signal_handlers(self) -> None:  # older uvicorn
        return None
