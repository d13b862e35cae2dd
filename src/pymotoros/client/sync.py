"""Blocking facade for scripts and notebooks: the async client on an event loop in a thread.

::

    with SyncRobotClient("192.168.1.31", robot="hc10") as robot:
        robot.enable()
        robot.move_joints([0, 0, 0, 0, -1.57, 0])

Every call of :class:`RobotClient` is here too, with the same name and parameters: both
classes inherit the one definition of each (:class:`~pymotoros.client.calls.RobotCalls`),
which blocks here (:mod:`pymotoros.client.blocking`), so a new client method cannot be
absent and mypy checks a blocking call against the async signature. The properties and
``states`` are this class's own. There is deliberately no ``__getattr__`` fallback: it
would make every attribute of this class type-check as ``Any``. Listeners run in the
loop's thread.

Interrupting a call (Ctrl-C: ``KeyboardInterrupt`` in the calling thread) cancels the
coroutine behind it and waits until that cancellation has run its course: a move sends
STOP_MOTION and waits for the robot at rest (at most ``EARLY_STOP_BOUND_S``, 3 s), and
the ``KeyboardInterrupt`` then goes on with a note saying where the robot stopped. A
second Ctrl-C during that wait does not cut the stop short.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import signal
import threading
import time
from collections.abc import AsyncIterator, Callable, Coroutine, Iterator
from types import TracebackType
from typing import Any, Final, ParamSpec, Self, TypeVar

from pymotoros.client.blocking import BlockingFacade
from pymotoros.client.calls import RobotCalls
from pymotoros.client.connection import Ports
from pymotoros.client.robot import RobotClient
from pymotoros.client.state import DEFAULT_STATE_TIMEOUT_S, JointState, RobotState, Status
from pymotoros.client.stopping import EARLY_STOP_BOUND_S, STOP_ON_THE_PENDANT
from pymotoros.client.tools import ToolTable
from pymotoros.models import ControllerModel, RobotModel
from pymotoros.protocol.constants import ByteOrder

_P = ParamSpec("_P")
_R = TypeVar("_R")

_THREAD_JOIN_TIMEOUT_S: Final = 5.0

INTERRUPT_WAIT_S: Final = EARLY_STOP_BOUND_S + 2.0
"""How long an interrupted call waits for its coroutine to finish cancelling: a move's
stop (:data:`EARLY_STOP_BOUND_S`) and a margin for the loop thread to get to it."""


class SyncRobotClient(BlockingFacade, RobotCalls):
    """Blocking :class:`RobotClient`: same constructor arguments, same methods.

    The calls are :class:`~pymotoros.client.calls.RobotCalls`' (the async client's): each
    coroutine method of it runs here on the facade's event loop and blocks until done
    (:mod:`pymotoros.client.blocking`). :meth:`stop` is safe from another thread while a
    blocking move runs there (the move raises ``MoveStoppedError``).
    """

    client: RobotClient

    def __init__(self, host: str = "127.0.0.1", **options: Any) -> None:
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(
            target=self._loop.run_forever, name="pymotoros-sync-client", daemon=True
        )
        self._thread.start()
        self.client = RobotClient(host, **options)
        """The async client behind this facade (use it only from the loop's thread)."""

    def run(self, coro: Coroutine[Any, Any, _R]) -> _R:
        """Run ``coro`` on the facade's event loop and block until it returns its result.

        For async code that must share the client's loop: an in-memory twin
        (:func:`pymotoros.testing.sync_twin` starts its servers this way), or a coroutine
        of :attr:`client` the facade does not wrap. Interrupting the call (Ctrl-C) cancels
        ``coro``, waits (at most :data:`INTERRUPT_WAIT_S`) until it has ended, a moving
        robot stopped, and re-raises the interrupt with the notes of that cancellation
        (where the robot stopped).
        """
        loop = self._loop
        done: concurrent.futures.Future[_R] = concurrent.futures.Future()
        notes: list[str] = []
        tasks: list[asyncio.Task[_R]] = []

        async def watched() -> _R:
            try:
                return await coro
            except asyncio.CancelledError as exc:
                notes.extend(getattr(exc, "__notes__", ()))
                raise

        def finished(task: asyncio.Task[_R]) -> None:
            if task.cancelled():
                done.cancel()
            elif (error := task.exception()) is not None:
                done.set_exception(error)
            else:
                done.set_result(task.result())

        def start() -> None:
            task = loop.create_task(watched())
            tasks.append(task)
            task.add_done_callback(finished)

        loop.call_soon_threadsafe(start)
        restore = _catch_sigterm()
        try:
            return done.result()
        except concurrent.futures.CancelledError as exc:
            for note in notes:  # cancelled from the loop's side (close() ended a move)
                exc.add_note(note)
            raise
        except BaseException as exc:
            if done.done():
                raise  # the coroutine's own error
            loop.call_soon_threadsafe(lambda: tasks and tasks[0].cancel("interrupted"))
            if not _wait_through_interrupts(done, INTERRUPT_WAIT_S):
                exc.add_note(
                    f"the interrupted call did not finish stopping within {INTERRUPT_WAIT_S:g} "
                    f"s: check that the robot stands ({STOP_ON_THE_PENDANT} if not)"
                )
            for note in notes:
                exc.add_note(note)
            if isinstance(exc, _Terminated):  # the robot is stopped: end as SIGTERM would
                restore()
                signal.raise_signal(signal.SIGTERM)
            raise
        finally:
            restore()

    def connect(self, *, motion: bool = True, state: bool = True, io: bool = True) -> Self:
        """Open the motion, state and IO connections (those asked for) and wait for them; returns
        self. ``with`` calls it."""
        self.run(self.client.connect(motion=motion, state=state, io=io))
        return self

    def close(self) -> None:
        """Close the connections and stop the loop thread. Idempotent."""
        if self._loop.is_closed():
            return
        try:
            self.run(self.client.close())
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(_THREAD_JOIN_TIMEOUT_S)
            self._loop.close()

    def __enter__(self) -> Self:
        try:
            return self.connect()
        except BaseException:
            self.close()
            raise

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # state (read-only snapshots are safe to read from any thread)

    @property
    def state(self) -> RobotState:
        """The latest state snapshot (frozen: safe to read from any thread)."""
        return self.client.state

    @property
    def status(self) -> Status | None:
        """The latest ROBOT_STATUS, or None before the first arrives."""
        return self.client.status

    def feedback(self, group: int = 0) -> JointState | None:
        """The latest joint feedback of ``group`` (None before the first)."""
        return self.client.feedback(group)

    def add_listener(self, listener: Callable[[RobotState], None]) -> Callable[[], None]:
        """``listener(state)`` on every state message, called in the loop's thread."""
        return self.client.add_listener(listener)

    def states(self, message_timeout_s: float = DEFAULT_STATE_TIMEOUT_S) -> Iterator[RobotState]:
        """Every state message, blocking between them."""
        iterator = self.client.states(message_timeout_s)
        try:
            while True:
                try:
                    yield self.run(_next(iterator))
                except StopAsyncIteration:
                    return
        finally:
            future = asyncio.run_coroutine_threadsafe(_aclose(iterator), self._loop)
            with contextlib.suppress(concurrent.futures.TimeoutError, RuntimeError):
                future.result(_THREAD_JOIN_TIMEOUT_S)

    @property
    def robot(self) -> RobotModel:
        """The robot model the client plans and checks with (joint names, limits)."""
        return self.client.robot

    @property
    def controller(self) -> ControllerModel:
        """The controller model: byte order and IO map used to check addresses."""
        return self.client.controller

    @property
    def host(self) -> str:
        """The controller's address, as given."""
        return self.client.host

    @property
    def ports(self) -> Ports:
        """The motion, state and IO ports in use."""
        return self.client.ports

    @property
    def order(self) -> ByteOrder:
        """The wire's byte order (big-endian for an FS100, little-endian otherwise)."""
        return self.client.order

    @property
    def timeout_s(self) -> float:
        """Longest wait for a reply to one request, in seconds."""
        return self.client.timeout_s

    @property
    def connect_timeout_s(self) -> float:
        """Longest wait for a TCP connection to open, in seconds."""
        return self.client.connect_timeout_s

    @property
    def tools(self) -> ToolTable:
        """The tool table ``tcp_pose`` uses (a plain object: safe from this thread)."""
        return self.client.tools

    def wait_for_first_state(self) -> None:
        """Block until the first state message is in (a no-op once it is): the calls that
        read the latest state (``tcp_pose``) wait for it when called right after
        connecting."""
        if not self.client.state.joints:
            self.run(self.client.wait_for_state())


class _Terminated(BaseException):
    """SIGTERM arrived while a call blocked (raised by :func:`_catch_sigterm`'s handler)."""


def _nothing() -> None:
    return None


def _catch_sigterm() -> Callable[[], None]:
    """While a call blocks in the main thread, SIGTERM with its default action (the
    process ends at once, the robot still moving) is caught instead: the call is
    interrupted like Ctrl-C (the robot stopped), then SIGTERM is raised again with the
    default action. A handler the program installed itself is left alone. Returns the
    function that puts the default back (idempotent)."""
    if threading.current_thread() is not threading.main_thread():
        return _nothing
    if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        return _nothing

    def terminated(_sig: int, _frame: object) -> None:
        raise _Terminated("SIGTERM")

    signal.signal(signal.SIGTERM, terminated)

    def restore() -> None:
        if signal.getsignal(signal.SIGTERM) is terminated:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)

    return restore


def _wait_through_interrupts(done: concurrent.futures.Future[Any], timeout_s: float) -> bool:
    """Wait until ``done`` is done, at most ``timeout_s``; a further Ctrl-C meanwhile is
    absorbed (the stop it would cut short is what the first one asked for). True if done."""
    deadline = time.monotonic() + timeout_s
    while not done.done():
        left = deadline - time.monotonic()
        if left <= 0:
            return False
        try:
            concurrent.futures.wait([done], timeout=left)
        except (KeyboardInterrupt, _Terminated):
            continue
    return True


async def _next(iterator: AsyncIterator[RobotState]) -> RobotState:
    return await anext(iterator)


async def _aclose(iterator: object) -> None:
    aclose = getattr(iterator, "aclose", None)
    if aclose is not None:
        await aclose()
