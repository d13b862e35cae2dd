"""An in-memory twin for tests: the client and a virtual controller, in virtual time.

As h11 pairs a client and a server connection and python-can offers a virtual bus,
:func:`twin` pairs a :class:`~pymotoros.client.RobotClient` with a
:class:`~pymotoros.controller.VirtualController` served by the real MotoROS server
handlers (motion, state, IO), over in-memory byte streams instead of TCP::

    from pymotoros.testing import twin

    async def test_pick_and_place() -> None:
        async with twin(robot="hc10") as (robot, cell):
            await robot.enable()
            await robot.move_joints([0.3, 0, 0, 0, -1.57, 0])   # seconds of motion, ms of test
            cell.controller.press_estop(True)                   # the operator's side

Everything runs on one :class:`VirtualClock`: the interpolation loop (one controller
tick per period), the state server's 25 ms cycle and the client's own waits (BUSY
back-off, following monitor, completion deadlines). Whenever the event loop has
nothing else to do, time jumps to the next deadline, so a minute of motion takes a
fraction of a second of wall time, and the same run gives the same result.

The byte streams are asyncio ``StreamReader``/``StreamWriter`` pairs over a small
in-memory transport (:func:`memory_stream_pair`) rather than ``socket.socketpair()``:
no file descriptors or system calls per message (a long trajectory is thousands of
round trips), delivery in a fixed order on the loop, and it runs wherever asyncio
does. The client and the servers use exactly the code they use over TCP.

The twin is in fidelity ``exact`` unless asked otherwise (``twin(fidelity="safe")``,
docs/fidelity.md): it behaves as MotoROS 1.9.12 where the robot is surprising. On the
in-memory pair a client's write lands in the server's stream at once, and one read of
the server returns what has landed, up to what it asks for (552 bytes in exact, as
``recv`` on the robot): a message written in two pieces with a read in between is
answered 3001, as the robot answers it.

This module sits on top of every layer (like the CLI); nothing in the package
imports it.
"""

from __future__ import annotations

import asyncio
import collections.abc
import contextlib
import dataclasses
import itertools
from collections.abc import AsyncIterator, Callable, Iterator
from typing import Any, Final, Self

from pymotoros.client.robot import RobotClient
from pymotoros.client.sync import SyncRobotClient
from pymotoros.controller import CellConfig, VirtualController, default_cell
from pymotoros.controller.lint import ClientLint, format_findings
from pymotoros.models import DEFAULT_CONTROLLER, DEFAULT_ROBOT, ControllerType, RobotModel
from pymotoros.models.fidelity import Fidelity
from pymotoros.protocol.constants import TCP_PORT_IO, TCP_PORT_MOTION, TCP_PORT_STATE
from pymotoros.runtime.clock import ManualClock
from pymotoros.runtime.io_server import IoServer
from pymotoros.runtime.motion_server import MotionServer
from pymotoros.runtime.state_server import STATE_PERIOD_S, StateServer
from pymotoros.runtime.tcp import ClientTasks, TcpService

__all__ = ["Twin", "VirtualClock", "memory_stream_pair", "ready_queue", "sync_twin", "twin"]

TWIN_HOST: Final = "twin"
"""The host name the twin's clients use (nothing resolves it: the connector is in memory)."""

TWIN_STATE_MESSAGE_GAP_S: Final = 0.0
"""The twin writes a state cycle's messages back to back (clients read them the same way;
``pymotoros sim`` spaces them by ``STATE_MESSAGE_GAP_S``, 1 ms): one wake-up per cycle
instead of one per message, about a tenth of the twin's cost per virtual second."""

SETTLE_TURNS: Final = 4
"""Event-loop turns the driver lets pass with nothing new to do before time jumps: a
request crosses the in-memory pair and is answered within two or three turns."""


# ------------------------------------------------------------------ in-memory streams


class _MemoryTransport(asyncio.Transport):
    """One end of an in-memory byte pipe: what one side writes, the other receives.

    A write lands in the peer's reader at once (its reading task wakes on the next loop
    turn, as after a socket read), in order; closing gives the peer EOF.
    """

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        protocol: asyncio.StreamReaderProtocol,
        *,
        name: str,
        peer_name: str,
    ) -> None:
        super().__init__({"peername": (peer_name, 0), "sockname": (name, 0), "socket": None})
        self._loop = loop
        self._protocol = protocol
        self._peer: _MemoryTransport | None = None
        self._closing = False
        self._eof = False
        self._paused = False
        self._held: list[bytes] = []
        self._limits = (0, 0)

    # writing
    def write(self, data: bytes | bytearray | memoryview) -> None:
        peer = self._peer
        if self._closing or self._eof or peer is None or peer._closing:
            return  # as a socket after shutdown: the bytes go nowhere
        peer._receive(bytes(data))

    def write_eof(self) -> None:
        if not self._eof and self._peer is not None:
            self._eof = True
            self._loop.call_soon(self._peer._receive_eof)

    def can_write_eof(self) -> bool:
        return True

    def get_write_buffer_size(self) -> int:
        return 0

    def get_write_buffer_limits(self) -> tuple[int, int]:
        return self._limits

    def set_write_buffer_limits(self, high: int | None = None, low: int | None = None) -> None:
        self._limits = (low or 0, high or 0)

    # reading
    def _receive(self, data: bytes) -> None:
        if self._closing:
            return
        if self._paused:
            self._held.append(data)
            return
        self._protocol.data_received(data)

    def _receive_eof(self) -> None:
        if not self._closing:
            self._protocol.eof_received()

    def pause_reading(self) -> None:
        self._paused = True

    def resume_reading(self) -> None:
        self._paused = False
        held, self._held = self._held, []
        for data in held:
            self._receive(data)

    def is_reading(self) -> bool:
        return not self._paused and not self._closing

    # closing
    def is_closing(self) -> bool:
        return self._closing

    def close(self) -> None:
        if self._closing:
            return
        self.write_eof()  # the peer reads EOF, as after a FIN
        self._closing = True
        self._held.clear()
        self._loop.call_soon(self._protocol.connection_lost, None)

    def abort(self) -> None:
        self.close()


_Streams = tuple[asyncio.StreamReader, asyncio.StreamWriter]


def memory_stream_pair(name_a: str = "a", name_b: str = "b") -> tuple[_Streams, _Streams]:
    """Two connected ``(reader, writer)`` pairs: bytes written on one side are read on the other.

    Call it inside a running event loop. Closing a writer gives the other side EOF.
    """
    loop = asyncio.get_running_loop()
    reader_a, reader_b = asyncio.StreamReader(), asyncio.StreamReader()
    proto_a = asyncio.StreamReaderProtocol(reader_a)
    proto_b = asyncio.StreamReaderProtocol(reader_b)
    end_a = _MemoryTransport(loop, proto_a, name=name_a, peer_name=name_b)
    end_b = _MemoryTransport(loop, proto_b, name=name_b, peer_name=name_a)
    end_a._peer, end_b._peer = end_b, end_a
    proto_a.connection_made(end_a)
    proto_b.connection_made(end_b)
    return (
        (reader_a, asyncio.StreamWriter(end_a, proto_a, reader_a, loop)),
        (reader_b, asyncio.StreamWriter(end_b, proto_b, reader_b, loop)),
    )


# ------------------------------------------------------------------ virtual time


class VirtualClock(ManualClock):
    """The twin's one time line, and its interpolation loop.

    A :class:`~pymotoros.runtime.clock.ManualClock` (``now``, ``sleep_until``: the
    state server sleeps on it) that is also a client clock (``sleep``), and that runs
    ``step`` (the controller's tick) once per ``period`` of virtual time itself:
    whenever the event loop is idle, :meth:`drive` runs the ticks due before the next
    sleeper's deadline back to back, stopping early if a tick wakes anyone (a reply
    the controller completed), then wakes the sleepers. A tick and the sleepers due at
    the same instant: the tick first, as the controller's reply is computed in it.
    """

    def __init__(
        self,
        start: float = 0.0,
        *,
        period: float | None = None,
        step: Callable[[], None] | None = None,
    ) -> None:
        super().__init__(start)
        if (period is None) != (step is None):
            raise ValueError("give both period and step, or neither")
        if period is not None and period <= 0:
            raise ValueError(f"period must be positive, got {period}")
        self.period = period
        self._step = step
        self._start = start
        self.ticks = 0
        """Ticks run so far (the tick at ``start`` is the first)."""
        self._tick_hooks: list[Callable[[], None]] = []

    def add_tick_hook(self, hook: Callable[[], None]) -> Callable[[], None]:
        """Call ``hook`` right after every tick (the controller's state is that tick's);
        returns the function that removes it.

        For tests that record what the controller did tick by tick (the commanded
        pulses of every tick: :meth:`Twin.commanded_pulses`) without reaching into the
        clock. A hook runs inside the time driver: it must not await or raise.
        """
        self._tick_hooks.append(hook)

        def remove() -> None:
            if hook in self._tick_hooks:
                self._tick_hooks.remove(hook)

        return remove

    def _tick_time(self, k: int) -> float:
        return self._start + k * (self.period or 0.0)

    async def sleep(self, seconds: float) -> None:
        """Let ``seconds`` of virtual time pass (the controller ticks meanwhile)."""
        await self.sleep_until(self.now() + max(seconds, 0.0))

    def _run_ticks_until(
        self, target: float | None, ready: collections.abc.Sized, *, batch: bool
    ) -> bool:
        """Run the ticks due at or before ``target``: all of them if ``batch``, else one.

        True once no tick is left before ``target`` and none woke anyone (the sleepers
        due at ``target`` may wake); False to come back after the loop has run.
        """
        step = self._step
        if step is None:
            return True
        while target is None or self._tick_time(self.ticks) <= target + _EPSILON:
            when = self._tick_time(self.ticks)
            if when > self.now():  # no sleeper is due before ``target``: only time moves
                self._now = when
            step()
            self.ticks += 1
            hooks = self._tick_hooks
            if hooks:
                for hook in tuple(hooks):
                    hook()
            if target is None or not batch or len(ready):
                return False
        return True

    async def drive(self, *, settle_turns: int = SETTLE_TURNS, watch_ready: bool = True) -> None:
        """Move time whenever the loop is idle; run until cancelled.

        Idle means no callback but this one is ready to run. Where :func:`ready_queue`
        sees the loop's ready callbacks, time jumps the moment everything waits, so a
        round trip costs no virtual time and a jump no extra loop turns, and ticks run
        back to back until one wakes someone. On a loop where it sees nothing (uvloop…),
        or with ``watch_ready=False``, ``settle_turns`` turns stand in for "idle" and
        time moves one tick or one deadline at a time.
        """
        ready = ready_queue(asyncio.get_running_loop()) if watch_ready else None
        batch = isinstance(ready, collections.abc.Sized)
        quiet: collections.abc.Sized = ready if isinstance(ready, collections.abc.Sized) else ()
        while True:
            if batch:
                await asyncio.sleep(0)
                if len(quiet):
                    continue  # someone else has work to do at virtual "now"
            else:
                for _ in range(settle_turns):
                    await asyncio.sleep(0)
            target = self.next_deadline
            if self._run_ticks_until(target, quiet, batch=batch) and target is not None:
                self.advance_to(max(target, self.now()))


def ready_queue(loop: asyncio.AbstractEventLoop) -> collections.abc.Sized | None:
    """The callbacks ``loop`` runs on its next turn (a live view), or None if unseen.

    Why it exists: virtual time may jump only when every task waits, and asyncio has no
    public "is the loop idle" query. CPython's own loops (every
    :class:`asyncio.BaseEventLoop`: the selector and proactor loops ``asyncio.run``
    makes) hold those callbacks in a deque, ``_ready``; this function is the one place
    pymotoros relies on that, so that the twin keeps its speed on any loop the caller
    runs, and ``tests/test_testing_pair.py`` pins it on the running Python (an asyncio
    change fails a test instead of silently slowing every twin). Any other loop (uvloop…)
    gives None: :meth:`VirtualClock.drive` then counts settle turns.
    """
    if not isinstance(loop, asyncio.BaseEventLoop):
        return None
    ready = vars(loop).get("_ready")
    return ready if isinstance(ready, collections.abc.Sized) else None


_EPSILON: Final = 1e-9
"""s: deadlines this close to a tick count as on it (sums of periods are not exact)."""


# ------------------------------------------------------------------ the twin


class Twin:
    """A virtual controller served in memory, on virtual time.

    ``controller`` is the :class:`~pymotoros.controller.VirtualController` (press
    E-stop, raise alarms, force IO…), ``clock`` the time line, ``motion``/``state``/
    ``io`` the MotoROS servers. :meth:`connect` is the client's connector;
    :meth:`client` builds a client wired to this twin. Start it with ``async with``.
    """

    def __init__(
        self,
        cell: CellConfig | None = None,
        *,
        robot: str | None = None,
        controller: str | ControllerType | None = None,
        state_period: float = STATE_PERIOD_S,
        state_message_gap: float = TWIN_STATE_MESSAGE_GAP_S,
        start_time: float = 0.0,
        fidelity: Fidelity | str | None = None,
    ) -> None:
        """``fidelity``: "exact" (MotoROS 1.9.12's surprises, docs/fidelity.md) or "safe";
        None keeps the cell's (``[motoros] fidelity``, exact by default)."""
        if cell is not None and (robot is not None or controller is not None):
            raise ValueError("give a cell, or robot/controller names, not both")
        cell = cell or default_cell(controller or DEFAULT_CONTROLLER, robot or DEFAULT_ROBOT)
        if fidelity is not None:
            cell = dataclasses.replace(cell, fidelity=Fidelity.parse(fidelity))
        self.cell = cell
        motion_clients = ClientTasks()  # a scenario's drop_motion closes these
        self.controller = VirtualController(self.cell, motion_link=motion_clients)
        self.clock = VirtualClock(
            start_time, period=self.controller.period_ms / 1000.0, step=self.controller.tick
        )
        order = self.cell.controller.byte_order
        self.motion = MotionServer(self.controller, order, clients=motion_clients)
        self.state = StateServer(
            self.controller, order, self.clock, period=state_period, message_gap=state_message_gap
        )
        self.io = IoServer(self.controller, order)
        self._services: dict[int, TcpService] = {
            TCP_PORT_MOTION: self.motion,
            TCP_PORT_STATE: self.state,
            TCP_PORT_IO: self.io,
        }
        self._crash: BaseException | None = None
        self._numbers = itertools.count(1)
        self._stop = asyncio.Event()
        self._started = asyncio.Event()
        self._runner: asyncio.Task[None] | None = None

    @property
    def robot(self) -> RobotModel:
        """The cell's groups as one robot model, for the client's planning and limits."""
        names = set(self.cell.robots)
        name = self.cell.robots[0] if len(names) == 1 else self.cell.name
        return RobotModel(name, f"twin of {self.cell.source}", self.cell.groups, frozenset())

    # ----------------------------------------------------------- life cycle

    async def start(self) -> Self:
        """Start the interpolation loop, the state cycle and virtual time."""
        if self._runner is not None:
            raise RuntimeError("this twin has already been started")
        self._runner = asyncio.create_task(self._serve(), name="pymotoros-twin")
        started = asyncio.create_task(self._started.wait())
        try:
            await asyncio.wait({self._runner, started}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            started.cancel()
        if self._runner.done():
            self._runner.result()  # raises what stopped it
        return self

    async def stop(self) -> None:
        """Close every client, stop the loops; re-raise a crash of the twin. Idempotent."""
        self._stop.set()
        if self._runner is not None:
            await self._runner

    async def __aenter__(self) -> Self:
        return await self.start()

    async def __aexit__(self, *exc_info: object) -> None:
        await self.stop()

    async def _serve(self) -> None:
        services = tuple(self._services.values())
        stop_cycles: Callable[[], None] | None = None
        async with asyncio.TaskGroup() as tg:
            for service in services:
                service.attach(tg)
            # The state cycle as clock callbacks writing to idle clients directly: the
            # simulator's broadcast task's bytes at the same virtual times, fewer loop turns.
            stop_cycles = self.state.schedule_cycles(self.clock, self._crashed)
            loops = [tg.create_task(self.clock.drive(), name="twin-virtual-time")]
            self._started.set()
            try:
                await self._stop.wait()
            finally:
                if stop_cycles is not None:
                    stop_cycles()
                for service in services:
                    await service.close_clients()
                for task in loops:
                    task.cancel()
        if self._crash is not None:
            raise self._crash

    def _crashed(self, exc: BaseException) -> None:
        """A state cycle failed: stop the twin; :meth:`stop` re-raises it."""
        if self._crash is None:
            self._crash = exc
        self._stop.set()

    # ----------------------------------------------------------- clients

    async def connect(self, host: str, port: int) -> _Streams:
        """The client's connector: a fresh in-memory connection to the server on ``port``
        (50240 motion, 50241 state, 50242 IO); other ports are refused like a closed one."""
        service = self._services.get(port)
        if service is None or self._runner is None or self._stop.is_set():
            raise ConnectionRefusedError(f"the twin serves nothing on port {port}")
        if not self.controller.motoros_started:  # as MotoROS's ports before its start-up
            raise ConnectionRefusedError(
                f"MotoROS is not listening on port {port}: {self.controller.motoros_phase}"
            )
        number = next(self._numbers)
        client_end, server_end = memory_stream_pair(
            f"{host}-client-{number}", f"{service.name}-{number}"
        )
        service.accept(*server_end)
        return client_end

    def client_options(self, **options: Any) -> dict[str, Any]:
        """:class:`RobotClient` keyword arguments that wire a client to this twin."""
        options.setdefault("controller", self.cell.controller)
        options.setdefault("robot", self.robot)
        return {**options, "clock": self.clock, "connector": self.connect}

    def client(self, **options: Any) -> RobotClient:
        """A :class:`RobotClient` for this twin (not connected yet); ``options`` as for it."""
        return RobotClient(TWIN_HOST, **self.client_options(**options))

    async def drop_clients(self) -> None:
        """Close every client connection at once, as a controller that dies would."""
        for service in self._services.values():
            await service.close_clients()

    async def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` of the twin's time (a shortcut for ``twin.clock.sleep``)."""
        await self.clock.sleep(seconds)

    # ----------------------------------------------------------- client lint

    @property
    def lint(self) -> ClientLint:
        """What the clients of this twin did that a real controller answers differently
        (``twin.lint.findings()``, ``twin.lint.clear()``; see :meth:`assert_no_lint`)."""
        return self.controller.lint

    def assert_no_lint(self) -> None:
        """Fail with the findings, as a table, if any client did something a robot
        would answer differently (issue 31)::

            async with twin(robot="hc10") as (client, cell):
                await my_driver_moves(client)
                cell.assert_no_lint()
        """
        findings = self.controller.lint.findings()
        if findings:
            raise AssertionError(format_findings(findings))

    # ----------------------------------------------------------- observing ticks

    def on_tick(self, hook: Callable[[], None]) -> Callable[[], None]:
        """Call ``hook`` after every controller tick; returns its remover
        (:meth:`VirtualClock.add_tick_hook`)."""
        return self.clock.add_tick_hook(hook)

    def commanded_pulses(self, group: int = 0) -> tuple[int, ...]:
        """The group's commanded pulses now (controller order, 8 slots): the initial
        position plus every increment executed (cheap enough to read every tick)."""
        return self.controller.commanded_pulses(group)

    def executed_this_tick(self) -> bool:
        """Whether the last tick executed a queue entry (IncMove sent increments to the
        servos, zero pulses included): the ticks a trajectory's duration counts."""
        c = self.controller
        return c.tick_count > 0 and c.last_increment_ms == c.time_ms


@contextlib.asynccontextmanager
async def twin(
    robot: str | None = None,
    controller: str | ControllerType | None = None,
    *,
    cell: CellConfig | None = None,
    fidelity: Fidelity | str | None = None,
    **client_options: Any,
) -> AsyncIterator[tuple[RobotClient, Twin]]:
    """``async with twin(robot="hc10") as (client, twin):`` a connected client and its twin.

    The client has received its first state; trajectory mode is not enabled yet
    (``await client.enable()``), as on a real controller at boot. ``fidelity``: "exact"
    (the default: MotoROS 1.9.12's surprises, docs/fidelity.md) or "safe".
    """
    the_twin = Twin(cell, robot=robot, controller=controller, fidelity=fidelity)
    async with the_twin, the_twin.client(**client_options) as client:
        await client.wait_for_state()
        yield client, the_twin


@contextlib.contextmanager
def sync_twin(
    robot: str | None = None,
    controller: str | ControllerType | None = None,
    *,
    cell: CellConfig | None = None,
    fidelity: Fidelity | str | None = None,
    **client_options: Any,
) -> Iterator[tuple[SyncRobotClient, Twin]]:
    """The blocking flavour: ``with sync_twin(robot="hc10") as (client, twin):``.

    The twin runs on the facade's event-loop thread; touch ``twin.controller`` only
    between calls. That loop is idle between calls, so virtual time runs on meanwhile,
    as fast as the thread goes (the robot at rest, the state stream flowing): keep the
    script's own work between calls short, or use the async :func:`twin`.
    ``fidelity`` as for :func:`twin`.
    """
    the_twin = Twin(cell, robot=robot, controller=controller, fidelity=fidelity)
    facade = SyncRobotClient(TWIN_HOST, **the_twin.client_options(**client_options))
    try:
        facade.run(the_twin.start())  # the facade's loop runs the twin too
        try:
            facade.connect()
            facade.wait_for_state()
            yield facade, the_twin
        finally:
            facade.run(facade.client.close())
            facade.run(the_twin.stop())
    finally:
        facade.close()
