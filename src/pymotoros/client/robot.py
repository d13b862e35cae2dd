"""``RobotClient``: drive a MotoROS controller (a real one or ``pymotoros sim``) over the wire.

::

    async with RobotClient("192.168.1.31", robot="hc10") as robot:
        await robot.enable()                        # START_TRAJ_MODE
        await robot.move_joints([0, 0, 0, 0, -1.57, 0])
        await robot.move_named("home")
        await robot.write_io_bit(10010, 1)

The client opens the motion, state and IO ports, keeps the latest state, sends
one request at a time per port and checks each reply's echo. Refusals become typed
exceptions (:mod:`pymotoros.client.errors`) carrying the code, its meaning and a
remedy. It imports no part of the virtual controller: it only speaks the wire.

``RobotClient`` is a facade over parts each testable on its own: the connections
(:class:`~pymotoros.client.link.Link`), the motion port's requests
(:class:`~pymotoros.client.motion_commands.MotionCommands`), the state stream and the
model checks (:class:`~pymotoros.client.state_view.StateView`), the IO image
(:class:`~pymotoros.client.io_port.IoPort`), joint motion
(:class:`~pymotoros.client.motion.Motion`) and the TCP
(:class:`~pymotoros.client.geometry.Geometry`). Its methods are those parts' methods,
forwarded with their names, parameters and documentation (:func:`_part`).
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Coroutine, Mapping
from pathlib import Path
from typing import Any, Concatenate, ParamSpec, Self, TypeVar

from pymotoros.client.avoid import Avoidance
from pymotoros.client.connection import (
    DEFAULT_CONNECT_TIMEOUT_S,
    DEFAULT_REQUEST_TIMEOUT_S,
    Connector,
    Ports,
)
from pymotoros.client.geometry import Geometry
from pymotoros.client.io_port import IoPort
from pymotoros.client.link import Link
from pymotoros.client.motion import Motion
from pymotoros.client.motion_commands import SLOW_COMMAND_TIMEOUT_S, MotionCommands
from pymotoros.client.move_result import MoveResult
from pymotoros.client.registers import RegisterValues, read_register_outputs, s1cxg_table
from pymotoros.client.state import RobotState, StateTracker, Status
from pymotoros.client.state_view import DH_TOLERANCE, StateView
from pymotoros.client.streaming import TrajectoryStreamer
from pymotoros.client.timing import REAL_TIME, ClientClock
from pymotoros.client.tools import ToolTable
from pymotoros.models import (
    DEFAULT_CONTROLLER,
    DEFAULT_ROBOT,
    ControllerModel,
    ControllerType,
    RobotModel,
    controller_model,
    robot_model,
)
from pymotoros.models.cell import CellModels, load_cell_models
from pymotoros.models.s1cxg import S1cxgTable

_P = ParamSpec("_P")
_R = TypeVar("_R")


def _part(
    part: str, method: Callable[Concatenate[Any, _P], _R]
) -> Callable[Concatenate[RobotClient, _P], _R]:
    """``RobotClient.<name>``: ``method`` called on the client's part ``part`` (an
    attribute name), with the method's name, parameters and documentation; a
    coroutine function stays one (``inspect.iscoroutinefunction``)."""
    name = method.__name__

    if inspect.iscoroutinefunction(method):

        async def forward_async(self: RobotClient, /, *args: Any, **kwargs: Any) -> Any:
            return await getattr(getattr(self, part), name)(*args, **kwargs)

        forward: Callable[..., Any] = forward_async
    else:

        def forward_plain(self: RobotClient, /, *args: Any, **kwargs: Any) -> Any:
            return getattr(getattr(self, part), name)(*args, **kwargs)

        forward = forward_plain
    functools.update_wrapper(forward, method)
    forward.__qualname__ = f"RobotClient.{name}"
    return forward


def _move_part(
    method: Callable[Concatenate[Geometry, _P], Coroutine[Any, Any, MoveResult]],
) -> Callable[Concatenate[RobotClient, _P], Coroutine[Any, Any, MoveResult]]:
    """:func:`_part` for a Cartesian move of ``_geometry``, holding the client's one move
    (:meth:`Motion.one_move`) from its first wait to its end: a second move is refused
    at once, and a stop() ends it even while it plans."""
    name = method.__name__

    async def forward(self: RobotClient, /, *args: _P.args, **kwargs: _P.kwargs) -> MoveResult:
        with self._motion.one_move(name):
            return await method(self._geometry, *args, **kwargs)

    functools.update_wrapper(forward, method)
    forward.__qualname__ = f"RobotClient.{name}"
    return forward


class RobotClient:
    """Async client for one MotoROS controller.

    ``controller`` picks the byte order (FS100 is big-endian) and the IO map used to
    check addresses; ``robot`` gives joint names and limits for planning. ``cell`` (a
    cell file or :class:`CellModels`) names both, and the tools' TCPs. ``tool`` is the
    tool in force on every group, when the user knows it (MotoROS cannot report it;
    see :mod:`pymotoros.client.tools`). Nothing is sent until :meth:`connect` (or
    ``async with``).

    ``clock`` is where the motion logic gets "now" and "sleep" (default: real time);
    ``connector`` opens a port's byte stream (default: TCP). The in-memory twin of
    :mod:`pymotoros.testing` passes both.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        *,
        ports: Ports | None = None,
        motion_port: int | None = None,
        state_port: int | None = None,
        io_port: int | None = None,
        controller: str | ControllerType | ControllerModel = DEFAULT_CONTROLLER,
        robot: str | RobotModel = DEFAULT_ROBOT,
        timeout_s: float = DEFAULT_REQUEST_TIMEOUT_S,
        connect_timeout_s: float = DEFAULT_CONNECT_TIMEOUT_S,
        clock: ClientClock = REAL_TIME,
        connector: Connector | None = None,
        cell: CellModels | str | Path | None = None,
        tool: int | None = None,
    ) -> None:
        tools: CellModels | None = None
        if cell is not None:  # a cell file names both the controller and the groups
            tools = cell = cell if isinstance(cell, CellModels) else load_cell_models(cell)
            controller, robot = cell.controller, cell.robot
        base = ports or Ports()
        self.host = host
        self.ports = Ports(
            motion=base.motion if motion_port is None else motion_port,
            state=base.state if state_port is None else state_port,
            io=base.io if io_port is None else io_port,
        )
        self.controller = (
            controller if isinstance(controller, ControllerModel) else controller_model(controller)
        )
        self.robot = robot if isinstance(robot, RobotModel) else robot_model(robot)
        self.order = self.controller.byte_order
        self.timeout_s = timeout_s
        self.connect_timeout_s = connect_timeout_s
        self.clock = clock
        self.connector = connector
        self.tools = ToolTable(self.robot, tools.tools if tools is not None else ())
        """Tool files the client knows and the tool in force (:mod:`pymotoros.client.tools`)."""
        if tool is not None:
            for index in range(len(self.robot.groups)):
                self.tools.use(tool, group=index)
        self.tracker = StateTracker(
            {i: g.num_axes for i, g in enumerate(self.robot.groups)}, now=clock.now
        )
        self._link = Link(
            host,
            self.ports,
            self.order,
            timeout_s=timeout_s,
            connect_timeout_s=connect_timeout_s,
            connector=connector,
        )
        self._commands = MotionCommands(self._link, self.tools, len(self.robot.groups))
        self.streamer = TrajectoryStreamer(
            self._commands, self.tracker, self.robot, self.controller, clock=clock
        )
        """Streams trajectories through this client's motion port (see :meth:`execute`)."""
        self._view = StateView(
            self._link, self.tracker, self.robot, self._commands.get_dh_parameters
        )
        self._io_port = IoPort(self._link, self.controller)
        self._motion = Motion(
            self._link,
            self._view,
            self._commands,
            self.streamer,
            self.robot,
            self.controller,
            Avoidance(tools, self.tools),
        )
        self._geometry = Geometry(self._view, self._motion, self.tools)

    # ------------------------------------------------------------------ connection

    async def connect(self, *, motion: bool = True, state: bool = True, io: bool = True) -> Self:
        """Open the ports asked for; on any failure close what was opened and raise."""
        await self._link.open(
            motion=motion,
            state=state,
            io=io,
            on_state=self.tracker.feed,
            on_state_lost=self.tracker.lost,
        )
        return self

    async def close(self) -> None:
        """Close every connection (trajectory mode is left as it is). Idempotent.

        A move still running in another task is ended first, as a cancellation ends it:
        STOP_MOTION, the robot at rest (at most ``EARLY_STOP_BOUND_S``, 3 s), then the
        connections close. (MotoROS does not clear its queues when the motion
        connection closes, §2.2: closing alone would leave the robot moving.)"""
        await self._motion.end_move("the client is closing")
        await self._link.close()

    async def __aenter__(self) -> Self:
        return await self.connect()

    async def __aexit__(self, *exc_info: object) -> None:
        await self.close()

    # ------------------------------------------------------------------ state

    @property
    def state(self) -> RobotState:
        """The latest state snapshot (empty until the first state message)."""
        return self.tracker.state

    @property
    def status(self) -> Status | None:
        """The latest ROBOT_STATUS (None before the first)."""
        return self.tracker.state.status

    feedback = _part("_view", StateView.feedback)
    add_listener = _part("_view", StateView.add_listener)
    states = _part("_view", StateView.states)
    wait_for_state = _part("_view", StateView.wait_for_state)
    wait_until = _part("_view", StateView.wait_until)
    check_groups = _part("_view", StateView.check_groups)
    check_dh_parameters = _part("_view", StateView.check_dh_parameters)
    group_index = _part("_view", StateView.group_index)

    # ------------------------------------------------------------------ motion port

    request_motion = _part("_commands", MotionCommands.request_motion)
    check_motion_ready = _part("_commands", MotionCommands.check_motion_ready)
    start_trajectory_mode = _part("_commands", MotionCommands.start_trajectory_mode)
    stop_trajectory_mode = _part("_commands", MotionCommands.stop_trajectory_mode)
    enable = start_trajectory_mode
    disable = stop_trajectory_mode
    start_servos = _part("_commands", MotionCommands.start_servos)
    stop_servos = _part("_commands", MotionCommands.stop_servos)
    reset_alarm = _part("_commands", MotionCommands.reset_alarm)
    stop_motion = _part("_commands", MotionCommands.stop_motion)
    queue_count = _part("_commands", MotionCommands.queue_count)
    select_tool = _part("_commands", MotionCommands.select_tool)
    get_dh_parameters = _part("_commands", MotionCommands.get_dh_parameters)
    ping = _part("_commands", MotionCommands.ping)

    # ------------------------------------------------------------------ IO

    read_io_bit = _part("_io_port", IoPort.read_io_bit)
    write_io_bit = _part("_io_port", IoPort.write_io_bit)
    read_io_group = _part("_io_port", IoPort.read_io_group)
    write_io_group = _part("_io_port", IoPort.write_io_group)
    read_mregister = _part("_io_port", IoPort.read_mregister)
    write_mregister = _part("_io_port", IoPort.write_mregister)

    async def read_register_outputs(
        self, table: S1cxgTable | Mapping[str, object] | str | Path, group: int = 0
    ) -> RegisterValues:
        """The S1CxG register outputs (TCP speed, Cartesian position, axis speeds and
        positions, pulses) decoded with ``table``: an :class:`S1cxgTable`, a
        ``{"330": 1, ...}`` mapping or a cell file with ``[groups.s1cxg]``."""
        if not isinstance(table, S1cxgTable):
            table = s1cxg_table(table, self.robot.groups[group], index=group)
        return await read_register_outputs(self.read_mregister, table, self.robot.groups[group])

    # ------------------------------------------------------------------ motion

    limits = _part("_motion", Motion.limits)
    current_positions = _part("_motion", Motion.current_positions)
    plan = _part("_motion", Motion.plan)
    execute = _part("_motion", Motion.execute)
    guard = _part("_motion", Motion.guard)
    stop = _part("_motion", Motion.stop)
    stop_threadsafe = _part("_motion", Motion.stop_threadsafe)
    move_joints = _part("_motion", Motion.move_joints)
    named_pose = _part("_motion", Motion.named_pose)
    move_named = _part("_motion", Motion.move_named)

    # ------------------------------------------------------------------ geometry

    tcp_pose = _part("_geometry", Geometry.tcp_pose)
    move_linear = _move_part(Geometry.move_linear)
    move_pose = _move_part(Geometry.move_pose)
    move_relative = _move_part(Geometry.move_relative)
    move_cartesian = _move_part(Geometry.move_cartesian)


async def connect(host: str = "127.0.0.1", **options: object) -> RobotClient:
    """``RobotClient(host, **options)`` connected; close it (or use ``async with``)."""
    client = RobotClient(host, **options)  # type: ignore[arg-type]
    return await client.connect()


__all__ = ["DH_TOLERANCE", "SLOW_COMMAND_TIMEOUT_S", "RobotClient", "connect"]
