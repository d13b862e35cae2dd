"""Blocking facade for scripts and notebooks: the async client on an event loop in a thread.

::

    with SyncRobotClient("192.168.1.31", robot="hc10") as robot:
        robot.enable()
        robot.move_joints([0, 0, 0, 0, -1.57, 0])

Every public method and property of :class:`RobotClient` has its twin here, with
the same name and parameters: coroutines become blocking calls, plain methods and
properties forward as they are (there is one implementation). A test compares the
two classes (``tests/test_front_door.py``), so a new client method cannot be silently
absent. There is deliberately no ``__getattr__`` fallback: it would make every attribute
of this class type-check as ``Any``. Listeners run in the loop's thread.
Interrupting a call (Ctrl-C) cancels the coroutine behind it.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import functools
import threading
from collections.abc import AsyncIterator, Callable, Coroutine, Iterator
from types import TracebackType
from typing import Any, Concatenate, Final, ParamSpec, Self, TypeVar

from pymotoros.client.connection import Ports
from pymotoros.client.robot import RobotClient
from pymotoros.client.state import DEFAULT_STATE_TIMEOUT_S, JointState, RobotState, Status
from pymotoros.client.tools import ToolTable
from pymotoros.models import ControllerModel, RobotModel
from pymotoros.protocol.constants import ByteOrder

_P = ParamSpec("_P")
_R = TypeVar("_R")

_THREAD_JOIN_TIMEOUT_S: Final = 5.0


def _forward(
    method: Callable[Concatenate[RobotClient, _P], Coroutine[Any, Any, _R]],
) -> Callable[Concatenate[SyncRobotClient, _P], _R]:
    """The blocking twin of an async ``RobotClient`` method (same name, parameters, doc)."""

    @functools.wraps(method)
    def blocking(self: SyncRobotClient, /, *args: _P.args, **kwargs: _P.kwargs) -> _R:
        return self.run(method(self.client, *args, **kwargs))

    blocking.__qualname__ = f"SyncRobotClient.{method.__name__}"
    return blocking


def _forward_plain(
    method: Callable[Concatenate[RobotClient, _P], _R],
) -> Callable[Concatenate[SyncRobotClient, _P], _R]:
    """A plain (non-async) ``RobotClient`` method called on the client behind the facade."""

    @functools.wraps(method)
    def plain(self: SyncRobotClient, /, *args: _P.args, **kwargs: _P.kwargs) -> _R:
        return method(self.client, *args, **kwargs)

    plain.__qualname__ = f"SyncRobotClient.{method.__name__}"
    return plain


def _after_first_state(
    method: Callable[Concatenate[RobotClient, _P], _R],
) -> Callable[Concatenate[SyncRobotClient, _P], _R]:
    """A plain method that reads the latest state, called once the first state is in:
    a script calls it right after connecting, before any state message has arrived."""

    @functools.wraps(method)
    def after(self: SyncRobotClient, /, *args: _P.args, **kwargs: _P.kwargs) -> _R:
        if not self.client.state.joints:
            self.run(self.client.wait_for_state())
        return method(self.client, *args, **kwargs)

    after.__qualname__ = f"SyncRobotClient.{method.__name__}"
    return after


class SyncRobotClient:
    """Blocking :class:`RobotClient`: same constructor arguments, same methods."""

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
        of :attr:`client` the facade does not wrap. Interrupting the call cancels ``coro``.
        """
        future = asyncio.run_coroutine_threadsafe(coro, self._loop)
        try:
            return future.result()
        except BaseException:
            future.cancel()
            raise

    def connect(self, *, motion: bool = True, state: bool = True, io: bool = True) -> Self:
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
        return self.client.state

    @property
    def status(self) -> Status | None:
        return self.client.status

    def feedback(self, group: int = 0) -> JointState | None:
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
        return self.client.robot

    @property
    def controller(self) -> ControllerModel:
        return self.client.controller

    @property
    def host(self) -> str:
        return self.client.host

    @property
    def ports(self) -> Ports:
        return self.client.ports

    @property
    def order(self) -> ByteOrder:
        return self.client.order

    @property
    def timeout_s(self) -> float:
        return self.client.timeout_s

    @property
    def connect_timeout_s(self) -> float:
        return self.client.connect_timeout_s

    @property
    def tools(self) -> ToolTable:
        """The tool table ``tcp_pose`` uses (a plain object: safe from this thread)."""
        return self.client.tools

    plan = _forward_plain(RobotClient.plan)
    limits = _forward_plain(RobotClient.limits)
    named_pose = _forward_plain(RobotClient.named_pose)
    group_index = _forward_plain(RobotClient.group_index)
    check_groups = _forward_plain(RobotClient.check_groups)
    guard = _forward_plain(RobotClient.guard)
    stop_threadsafe = _forward_plain(RobotClient.stop_threadsafe)

    wait_for_state = _forward(RobotClient.wait_for_state)
    wait_until = _forward(RobotClient.wait_until)
    request_motion = _forward(RobotClient.request_motion)
    check_motion_ready = _forward(RobotClient.check_motion_ready)
    start_trajectory_mode = _forward(RobotClient.start_trajectory_mode)
    stop_trajectory_mode = _forward(RobotClient.stop_trajectory_mode)
    enable = _forward(RobotClient.start_trajectory_mode)
    disable = _forward(RobotClient.stop_trajectory_mode)
    start_servos = _forward(RobotClient.start_servos)
    stop_servos = _forward(RobotClient.stop_servos)
    reset_alarm = _forward(RobotClient.reset_alarm)
    stop_motion = _forward(RobotClient.stop_motion)
    stop = _forward(RobotClient.stop)
    """Safe from another thread while a blocking move runs there (it raises MoveStoppedError)."""
    queue_count = _forward(RobotClient.queue_count)
    select_tool = _forward(RobotClient.select_tool)
    get_dh_parameters = _forward(RobotClient.get_dh_parameters)
    check_dh_parameters = _forward(RobotClient.check_dh_parameters)
    ping = _forward(RobotClient.ping)
    read_io_bit = _forward(RobotClient.read_io_bit)
    write_io_bit = _forward(RobotClient.write_io_bit)
    read_io_group = _forward(RobotClient.read_io_group)
    write_io_group = _forward(RobotClient.write_io_group)
    read_mregister = _forward(RobotClient.read_mregister)
    write_mregister = _forward(RobotClient.write_mregister)
    current_positions = _forward(RobotClient.current_positions)
    execute = _forward(RobotClient.execute)
    move_joints = _forward(RobotClient.move_joints)
    move_named = _forward(RobotClient.move_named)
    move_linear = _forward(RobotClient.move_linear)
    move_relative = _forward(RobotClient.move_relative)
    move_pose = _forward(RobotClient.move_pose)
    read_register_outputs = _forward(RobotClient.read_register_outputs)
    move_cartesian = _forward(RobotClient.move_cartesian)
    tcp_pose = _after_first_state(RobotClient.tcp_pose)


async def _next(iterator: AsyncIterator[RobotState]) -> RobotState:
    return await anext(iterator)


async def _aclose(iterator: object) -> None:
    aclose = getattr(iterator, "aclose", None)
    if aclose is not None:
        await aclose()
