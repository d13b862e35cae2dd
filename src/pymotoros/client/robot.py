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

``RobotClient`` builds the connections (:class:`~pymotoros.client.link.Link`) and the
parts its calls work through (:class:`~pymotoros.client.calls.ClientParts`); the calls
themselves are defined once, in :class:`~pymotoros.client.calls.RobotCalls`, for this
client and its blocking facade (:class:`~pymotoros.client.SyncRobotClient`).
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from pathlib import Path
from typing import Self

from pymotoros.client.avoid import Avoidance
from pymotoros.client.calls import ClientParts, RobotCalls
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
from pymotoros.client.state import DEFAULT_STATE_TIMEOUT_S, RobotState, StateTracker, Status
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


class RobotClient(RobotCalls):
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

    Its calls (``move_joints``, ``read_io_bit`` ...) are those of
    :class:`~pymotoros.client.calls.RobotCalls`, which :class:`SyncRobotClient` inherits
    too; this class adds the connection, the latest state and :meth:`states`.
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
        commands = MotionCommands(self._link, self.tools, len(self.robot.groups))
        self.streamer = TrajectoryStreamer(
            commands, self.tracker, self.robot, self.controller, clock=clock
        )
        """Streams trajectories through this client's motion port (see :meth:`execute`)."""
        view = StateView(self._link, self.tracker, self.robot, commands.get_dh_parameters)
        motion = Motion(
            self._link,
            view,
            commands,
            self.streamer,
            self.robot,
            self.controller,
            Avoidance(tools, self.tools),
        )
        self._parts = ClientParts(
            view=view,
            commands=commands,
            io=IoPort(self._link, self.controller),
            motion=motion,
            geometry=Geometry(view, motion, self.tools),
            robot=self.robot,
        )

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
        await self._parts.motion.end_move("the client is closing")
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

    def states(
        self, message_timeout_s: float = DEFAULT_STATE_TIMEOUT_S
    ) -> AsyncIterator[RobotState]:
        """``async for state in robot.states():`` every state message, latest wins."""
        return self._parts.view.states(message_timeout_s)


async def connect(host: str = "127.0.0.1", **options: object) -> RobotClient:
    """``RobotClient(host, **options)`` connected; close it (or use ``async with``)."""
    client = RobotClient(host, **options)  # type: ignore[arg-type]
    return await client.connect()


__all__ = ["DH_TOLERANCE", "SLOW_COMMAND_TIMEOUT_S", "RobotClient", "connect"]
