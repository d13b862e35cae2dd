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
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import time
from collections.abc import AsyncIterator, Callable, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Final, Literal, Self, TypeVar

from pymotoros.client import io_map
from pymotoros.client.connection import (
    DEFAULT_CONNECT_TIMEOUT_S,
    DEFAULT_REQUEST_TIMEOUT_S,
    Connector,
    FrameConnection,
    Ports,
)
from pymotoros.client.errors import (
    ClientError,
    ConnectionLostError,
    GroupError,
    ModelMismatchError,
    MoveStoppedError,
    io_error,
    reply_error,
)
from pymotoros.client.motion_port import MotionReadiness
from pymotoros.client.planning import (
    DEFAULT_SAMPLE_PERIOD_S,
    JointLimits,
    JointTrajectory,
    PlanningError,
    plan_joint_move,
)
from pymotoros.client.registers import RegisterValues, read_register_outputs, s1cxg_table
from pymotoros.client.srdf import NamedPose, find_pose, parse_srdf
from pymotoros.client.state import (
    DEFAULT_STATE_TIMEOUT_S,
    JointState,
    Listener,
    RobotState,
    StateTracker,
    Status,
)
from pymotoros.client.streaming import (
    DEFAULT_BUSY_TIMEOUT_S,
    DEFAULT_GOAL_TOLERANCE,
    FollowingSample,
    MoveResult,
    TrajectoryStreamer,
)
from pymotoros.client.timing import REAL_TIME, ClientClock
from pymotoros.client.tools import DEFAULT_TCP_SPEED_MM_S, ToolTable
from pymotoros.errors import KinematicsError
from pymotoros.models import (
    DEFAULT_CONTROLLER,
    DEFAULT_ROBOT,
    ROBOTS,
    ControllerModel,
    ControllerType,
    RobotModel,
    controller_model,
    robot_model,
)
from pymotoros.models.cell import CellModels, load_cell_models
from pymotoros.models.s1cxg import S1cxgTable
from pymotoros.protocol.constants import (
    MAX_TOOL_NUMBER,
    ByteOrder,
    IoResultCode,
    MotionCommand,
    NotReadySubcode,
    Port,
    ResultCode,
)
from pymotoros.protocol.messages import (
    DhLink,
    IoErrorReply,
    Message,
    MotoGetDhParameters,
    MotoGetDhParametersReply,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoReadIoBit,
    MotoReadIoBitReply,
    MotoReadIoGroup,
    MotoReadIoGroupReply,
    MotoReadMRegister,
    MotoReadMRegisterReply,
    MotoSelectTool,
    MotoWriteIoBit,
    MotoWriteIoBitReply,
    MotoWriteIoGroup,
    MotoWriteIoGroupReply,
    MotoWriteMRegister,
    MotoWriteMRegisterReply,
    Ping,
    PingReply,
    WireMessage,
)

logger = logging.getLogger(__name__)

SLOW_COMMAND_TIMEOUT_S: Final = 20.0
"""START_TRAJ_MODE may wait 5 s for servo power and 5 s for the job (§3.2); servo commands
wait up to 5 s (§3.1)."""

DH_TOLERANCE: Final = 1e-4
"""DH parameters travel as float32 (reference §1.5): ~1e-7 relative; 0.1 mm / 0.1 mrad is
far below any real difference between two robot models."""

_SLOW_COMMANDS: Final = frozenset(
    {
        MotionCommand.START_TRAJ_MODE,
        MotionCommand.START_SERVOS,
        MotionCommand.STOP_SERVOS,
        MotionCommand.STOP_TRAJ_MODE,
    }
)


class RobotClient:
    """Async client for one MotoROS controller.

    ``controller`` picks the byte order (FS100 is big-endian) and the IO map used to
    check addresses; ``robot`` gives joint names and limits for planning. Nothing is
    sent until :meth:`connect` (or ``async with``).

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
    ) -> None:
        if cell is not None:  # a cell file names both the controller and the groups
            cell = cell if isinstance(cell, CellModels) else load_cell_models(cell)
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
        self.order: ByteOrder = self.controller.byte_order
        self.timeout_s = timeout_s
        self.connect_timeout_s = connect_timeout_s
        self.clock = clock
        self.connector = connector
        self.tracker = StateTracker(
            {i: g.num_axes for i, g in enumerate(self.robot.groups)}, now=clock.now
        )
        self.streamer = TrajectoryStreamer(
            self, self.tracker, self.robot, self.controller, clock=clock
        )
        """Streams trajectories through this client's motion port (see :meth:`execute`)."""
        self._motion: FrameConnection | None = None
        self._state_conn: FrameConnection | None = None
        self._io: FrameConnection | None = None
        self._sequence = itertools.count(1)
        self.tools = ToolTable(self.robot)
        """Tool offsets the client knows (:meth:`ToolTable.define`) and the selected ones."""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._moving: asyncio.Task[object] | None = None
        self._stop_requested = False

    # ------------------------------------------------------------------ connection

    async def connect(self, *, motion: bool = True, state: bool = True, io: bool = True) -> Self:
        """Open the ports asked for; on any failure close what was opened and raise."""
        self._loop = asyncio.get_running_loop()
        try:
            if motion:
                self._motion = await self._open(Port.MOTION)
            if state:
                self._state_conn = await self._open(
                    Port.STATE, on_topic=self.tracker.feed, on_lost=self.tracker.lost
                )
            if io:
                self._io = await self._open(Port.IO)
        except BaseException:
            await self.close()
            raise
        return self

    async def _open(
        self,
        kind: Port,
        *,
        on_topic: Callable[[WireMessage], None] | None = None,
        on_lost: Callable[[ConnectionLostError], None] | None = None,
    ) -> FrameConnection:
        return await FrameConnection.open(
            self.host,
            self.ports.of(kind),
            kind,
            self.order,
            timeout_s=self.connect_timeout_s,
            on_topic=on_topic,
            on_lost=on_lost,
            connector=self.connector,
        )

    async def close(self) -> None:
        """Close every connection (trajectory mode is left as it is). Idempotent."""
        for conn in (self._io, self._state_conn, self._motion):
            if conn is not None:
                await conn.close()

    async def __aenter__(self) -> Self:
        return await self.connect()

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.close()

    def _need(self, conn: FrameConnection | None, kind: Port) -> FrameConnection:
        if conn is None:
            raise ClientError(
                f"the {kind.value} port is not connected (connect({kind.value}=True))"
            )
        return conn

    # ------------------------------------------------------------------ state

    @property
    def state(self) -> RobotState:
        """The latest state snapshot (empty until the first state message)."""
        return self.tracker.state

    @property
    def status(self) -> Status | None:
        return self.tracker.state.status

    def feedback(self, group: int = 0) -> JointState | None:
        return self.tracker.state.joints.get(group)

    def add_listener(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(state)`` on every state message; returns the function that removes it."""
        return self.tracker.add_listener(listener)

    def states(
        self, message_timeout_s: float = DEFAULT_STATE_TIMEOUT_S
    ) -> AsyncIterator[RobotState]:
        """``async for state in robot.states():`` every state message, latest wins."""
        return self.tracker.states(message_timeout_s)

    async def wait_for_state(self, timeout_s: float = DEFAULT_STATE_TIMEOUT_S) -> RobotState:
        """Wait for a full state cycle: ROBOT_STATUS and every group's feedback.

        The groups the controller streams are checked against the robot model: other
        groups, or more axes than the model has, raise :class:`ModelMismatchError`.
        """
        self._need(self._state_conn, Port.STATE)
        tracker = self.tracker
        await tracker.wait_for(
            lambda s: tracker.groups_seen is not None,
            timeout_s,
            what="a full state cycle (feedback of every group, then ROBOT_STATUS)",
        )
        self.check_groups()
        groups = range(len(self.robot.groups))
        return await tracker.wait_for(
            lambda s: s.status is not None and all(g in s.joints for g in groups),
            timeout_s,
            what="the first status and feedback from the state port",
        )

    def check_groups(self) -> None:
        """Compare the groups seen on the state stream with the robot model (no-op before)."""
        seen = self.tracker.groups_seen
        if seen is None:
            return
        model = self.robot
        expected = {i: g.num_axes for i, g in enumerate(model.groups)}
        problems = [
            f"group {i} ({model.groups[i].name}, {n} axes) sends no feedback"
            for i, n in expected.items()
            if i not in seen
        ]
        problems += [
            f"group {i} streams at least {seen[i]} axes, the model has {n}"
            for i, n in expected.items()
            if i in seen and seen[i] > n
        ]
        extra = sorted(set(seen) - set(expected))
        if extra:
            problems.append(f"the controller also streams group(s) {', '.join(map(str, extra))}")
        if problems:
            described = ", ".join(f"{g.name} {g.num_axes} axes" for g in model.groups)
            streamed = ", ".join(f"group {i}" for i in sorted(seen)) or "no group"
            raise ModelMismatchError(
                f"model mismatch: {model.name} expects {len(expected)} group(s) ({described}) "
                f"but the controller streams {len(seen)} ({streamed}): "
                + "; ".join(problems)
                + ". Give the controller's robot with --robot, or its cell file with --config"
            )

    async def check_dh_parameters(self) -> None:
        """Compare the controller's DH parameters (MOTO_GET_DH_PARAMETERS) with the model's.

        Two models with the same groups and axes (HC10 and GP12) look the same on the
        state stream; their DH parameters differ. Raises :class:`ModelMismatchError`
        naming the first difference, and the known robot whose parameters match. Opt-in:
        on a MotoROS whose library fails the request the connection is closed (§5.9).
        """
        streamed = await self.get_dh_parameters()
        for index, group in enumerate(self.robot.groups):
            if not group.dh or index >= len(streamed):
                continue
            links = streamed[index]
            for n, (model, seen) in enumerate(zip(group.dh, links, strict=False)):
                for field in ("theta", "d", "a", "alpha"):
                    want, got = getattr(model, field), getattr(seen, field)
                    if abs(want - got) > DH_TOLERANCE:
                        matches = [
                            name
                            for name, robot in ROBOTS.items()
                            if robot.groups
                            and robot.groups[0].dh
                            and _dh_matches(robot.groups[0].dh, links)
                        ]
                        hint = (
                            f"they match {', '.join(matches)}: give --robot {matches[0]}"
                            if matches
                            else "give the controller's robot with --robot or --config"
                        )
                        raise ModelMismatchError(
                            f"model mismatch: the controller's DH parameters are not "
                            f"{self.robot.name}'s (group {index} {group.name}, link {n + 1}: "
                            f"{field} {got:.4f} on the controller, {want:.4f} in the model); "
                            + hint
                        )

    def group_index(self, group: int | str) -> int:
        """The number of a group given by number (0, 1 …) or name (R1, r2, B1 …)."""
        groups = self.robot.groups
        if isinstance(group, str):
            text = group.strip()
            if text.isdigit():
                group = int(text)
            else:
                for i, g in enumerate(groups):
                    if g.name.lower() == text.lower():
                        return i
                raise GroupError(f"no group {text!r}: {self._describe_groups()}")
        if not 0 <= group < len(groups):
            raise GroupError(f"no group {group}: {self._describe_groups()}")
        return group

    def _describe_groups(self) -> str:
        listed = ", ".join(
            f"{g.name} (group {i}, {g.num_axes} axes)" for i, g in enumerate(self.robot.groups)
        )
        return (
            f"{self.robot.name} has {listed}; a multi-arm cell is described with "
            "--config CELL.toml (RobotClient(cell=...))"
        )

    async def wait_until(
        self, predicate: Callable[[RobotState], bool], timeout_s: float, what: str = "the condition"
    ) -> RobotState:
        """Wait until ``predicate(state)`` holds (checked on every state message)."""
        return await self.tracker.wait_for(predicate, timeout_s, what=what)

    # ------------------------------------------------------------------ motion port

    async def request_motion(
        self, message: WireMessage, *, timeout_s: float | None = None
    ) -> MotoMotionReply:
        """Send a motion-port request answered by a MOTO_MOTION_REPLY; returns it as is."""
        conn = self._need(self._motion, Port.MOTION)
        reply = await conn.request(message, MotoMotionReply, timeout_s=timeout_s or self.timeout_s)
        if not isinstance(reply, MotoMotionReply):
            raise ClientError(f"unexpected reply {reply!r} to {message!r}")
        return reply

    async def _command(self, command: MotionCommand, group: int = 0) -> MotoMotionReply:
        sequence = next(self._sequence) % 2**31
        wait = SLOW_COMMAND_TIMEOUT_S if command in _SLOW_COMMANDS else self.timeout_s
        return await self.request_motion(
            MotoMotionCtrl(group, sequence, int(command)), timeout_s=max(wait, self.timeout_s)
        )

    async def _command_ok(self, command: MotionCommand, group: int = 0) -> None:
        reply = await self._command(command, group)
        if reply.result != ResultCode.SUCCESS:
            raise reply_error(reply.result, reply.subcode, reply.command)

    async def check_motion_ready(self) -> MotionReadiness:
        """CHECK_MOTION_READY: ready, or the NOT_READY reason (never raises for "not ready")."""
        reply = await self._command(MotionCommand.CHECK_MOTION_READY)
        if reply.result == ResultCode.SUCCESS:
            return MotionReadiness(True, 0, None, "ready", "")
        err = reply_error(reply.result, reply.subcode, reply.command)
        try:
            reason: NotReadySubcode | None = NotReadySubcode(reply.subcode)
        except ValueError:
            reason = None
        return MotionReadiness(False, reply.subcode, reason, err.meaning, err.remedy)

    async def start_trajectory_mode(self) -> None:
        """START_TRAJ_MODE: servo on, start INIT_ROS, wait until motion is possible.

        Raises :class:`NotReadyError` (``.reason``) when the controller cannot get there.
        """
        await self._command_ok(MotionCommand.START_TRAJ_MODE)

    async def stop_trajectory_mode(self) -> None:
        """STOP_TRAJ_MODE: end the INIT_ROS job (fails while motion is queued)."""
        await self._command_ok(MotionCommand.STOP_TRAJ_MODE)

    enable = start_trajectory_mode
    disable = stop_trajectory_mode

    async def start_servos(self) -> None:
        await self._command_ok(MotionCommand.START_SERVOS)

    async def stop_servos(self) -> None:
        await self._command_ok(MotionCommand.STOP_SERVOS)

    async def reset_alarm(self) -> None:
        """RESET_ALARM: reset alarms and cancel errors (not waited on by MotoROS)."""
        await self._command_ok(MotionCommand.RESET_ALARM)

    async def stop_motion(self) -> None:
        """STOP_MOTION: stop at once and clear every queue (no ramp from MotoROS)."""
        await self._command_ok(MotionCommand.STOP_MOTION)

    async def queue_count(self, group: int = 0) -> int:
        """Increments still queued for ``group`` (CHECK_QUEUE_CNT: the count is the subcode)."""
        reply = await self._command(MotionCommand.CHECK_QUEUE_CNT, group)
        if reply.result != ResultCode.SUCCESS:
            raise reply_error(reply.result, reply.subcode, reply.command)
        return reply.subcode

    async def select_tool(self, tool: int, group: int = 0) -> None:
        """MOTO_SELECT_TOOL: the tool file ``group`` moves with from its next segment on."""
        if not 0 <= tool <= MAX_TOOL_NUMBER:
            raise ValueError(f"tool {tool}: tool numbers are 0..{MAX_TOOL_NUMBER}")
        sequence = next(self._sequence) % 2**31
        reply = await self.request_motion(MotoSelectTool(group, tool, sequence))
        if reply.result != ResultCode.SUCCESS:
            raise reply_error(reply.result, reply.subcode, reply.command)
        self.tools.selected[group] = tool

    async def get_dh_parameters(self) -> tuple[tuple[DhLink, ...], ...]:
        """DH parameters (theta, d, a, alpha) of each of the robot's groups."""
        conn = self._need(self._motion, Port.MOTION)
        reply = await conn.request(
            MotoGetDhParameters(), MotoGetDhParametersReply, timeout_s=self.timeout_s
        )
        return _expect(reply, MotoGetDhParametersReply).groups[: len(self.robot.groups)]

    async def ping(self) -> float:
        """PING on the motion port; returns the round trip in seconds."""
        conn = self._need(self._motion, Port.MOTION)
        start = time.perf_counter()
        _expect(await conn.request(Ping(), PingReply, timeout_s=self.timeout_s), PingReply)
        return time.perf_counter() - start

    # ------------------------------------------------------------------ IO

    async def _io_request(
        self, message: Message, expected: type[Message], address: int, what: str, *, io_only: bool
    ) -> WireMessage:
        conn = self._io if self._io is not None or io_only else self._motion
        conn = self._need(conn, Port.IO)
        reply = await conn.request(message, expected, timeout_s=self.timeout_s)
        if isinstance(reply, IoErrorReply):
            raise reply_error(reply.result, reply.subcode, int(message.MSG_TYPE))
        if isinstance(reply, MotoMotionReply):
            raise reply_error(reply.result, reply.subcode, reply.command)
        code = getattr(reply, "result_code", IoResultCode.OK)
        if code != IoResultCode.OK:
            raise io_error(code, address, what)
        return reply

    async def read_io_bit(self, address: int, *, check: bool = True) -> int:
        """Read one IO bit (e.g. 10010 = general output OT#1)."""
        if check:
            io_map.check_bit_address(self.controller, address, write=False)
        reply = await self._io_request(
            MotoReadIoBit(address), MotoReadIoBitReply, address, "IO read", io_only=False
        )
        return _expect(reply, MotoReadIoBitReply).value

    async def write_io_bit(self, address: int, value: int, *, check: bool = True) -> None:
        """Write one IO bit (general outputs, network inputs, interface panel only)."""
        if check:
            io_map.check_bit_address(self.controller, address, write=True)
            io_map.check_bit_value(address, value)
        await self._io_request(
            MotoWriteIoBit(address, value), MotoWriteIoBitReply, address, "IO write", io_only=False
        )

    async def read_io_group(self, address: int, *, check: bool = True) -> int:
        """Read 8 bits; ``address`` is the byte number (1001 = bits 10010..10017)."""
        if check:
            io_map.check_group_address(self.controller, address, write=False)
        reply = await self._io_request(
            MotoReadIoGroup(address), MotoReadIoGroupReply, address, "IO group read", io_only=False
        )
        return _expect(reply, MotoReadIoGroupReply).value

    async def write_io_group(self, address: int, value: int, *, check: bool = True) -> None:
        """Write 8 bits (0..255, bit 0 first) to byte ``address``."""
        if check:
            io_map.check_group_address(self.controller, address, write=True)
            io_map.check_group_value(address, value)
        await self._io_request(
            MotoWriteIoGroup(address, value),
            MotoWriteIoGroupReply,
            address,
            "IO group write",
            io_only=False,
        )

    async def read_mregister(self, number: int, *, check: bool = True) -> int:
        """Read M-register ``number`` (0..999; IO port only)."""
        n = io_map.normalise_mregister(number, write=False) if check else number
        reply = await self._io_request(
            MotoReadMRegister(n), MotoReadMRegisterReply, number, "M-register read", io_only=True
        )
        return _expect(reply, MotoReadMRegisterReply).value

    async def write_mregister(self, number: int, value: int, *, check: bool = True) -> None:
        """Write M-register ``number`` (0..559) with 0..65535 (IO port only)."""
        n = number
        if check:
            n = io_map.normalise_mregister(number, write=True)
            io_map.check_mregister_value(number, value)
        await self._io_request(
            MotoWriteMRegister(n, value),
            MotoWriteMRegisterReply,
            number,
            "M-register write",
            io_only=True,
        )

    # ------------------------------------------------------------------ motion

    def limits(self, group: int | str = 0) -> JointLimits:
        """Planning limits of ``group`` from the robot model."""
        return JointLimits.from_group(
            self.robot.groups[self.group_index(group)],
            self.controller.interpolation_period_ms,
            self.controller.float_mode,
        )

    async def current_positions(
        self, group: int | Sequence[int] = 0, *, at_rest: bool = True, timeout_s: float = 10.0
    ) -> tuple[float, ...]:
        """Joint positions from feedback; with ``at_rest``, once the robot is settled."""
        groups = _groups(group)
        await self.wait_for_state()
        if at_rest:
            return await self.streamer.wait_until_at_rest(groups, timeout_s=timeout_s)
        state = self.state
        return tuple(v for g in groups for v in (state.positions(g) or ()))

    def plan(
        self,
        start: Sequence[float],
        goal: Sequence[float],
        *,
        groups: Sequence[int] = (0,),
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        sample_period: float = DEFAULT_SAMPLE_PERIOD_S,
    ) -> JointTrajectory:
        """A synchronised point-to-point move (see :func:`planning.plan_joint_move`)."""
        limits = JointLimits.concat([self.limits(g) for g in groups])
        return plan_joint_move(
            start,
            goal,
            limits,
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
            sample_period=sample_period,
        )

    async def execute(
        self,
        trajectory: JointTrajectory,
        *,
        groups: Sequence[int] = (0,),
        busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        timeout_s: float | None = None,
        check_speed: bool = True,
        on_progress: Callable[[FollowingSample], None] | None = None,
    ) -> MoveResult:
        """Stream ``trajectory`` and wait until the robot has settled at its last point.

        The trajectory's joints are those of ``groups`` one after the other; one group
        goes as JOINT_TRAJ_PT_FULL, several as JOINT_TRAJ_PT_FULL_EX.
        """
        self._need(self._state_conn, Port.STATE)  # completion is judged from the state stream
        groups = tuple(self.group_index(g) for g in groups)
        task = asyncio.current_task()
        self._moving = task
        self._stop_requested = False
        try:
            return await self.streamer.execute(
                trajectory,
                groups,
                busy_timeout_s=busy_timeout_s,
                goal_tolerance=goal_tolerance,
                timeout_s=timeout_s,
                check_speed=check_speed,
                on_progress=on_progress,
            )
        except asyncio.CancelledError:
            if not self._stop_requested or task is None:
                raise
            task.uncancel()
            here = tuple(v for g in groups for v in (self.state.positions(g) or ()))
            where = ", ".join(f"{v:.4f}" for v in here)
            raise MoveStoppedError(
                f"move stopped on request (STOP_MOTION) at [{where}]", positions=here
            ) from None
        finally:
            self._moving = None

    async def stop(self) -> None:
        """Stop the robot now (STOP_MOTION) and end a move running in another task.

        Safe from another task of the client's loop while :meth:`execute` /
        :meth:`move_joints` runs: that call raises :class:`MoveStoppedError`. From
        another thread use :meth:`stop_threadsafe`.
        """
        moving = self._moving
        if moving is not None and moving is not asyncio.current_task():
            self._stop_requested = True
            moving.cancel()
        await self.stop_motion()

    def stop_threadsafe(self, timeout_s: float = DEFAULT_REQUEST_TIMEOUT_S) -> None:
        """:meth:`stop` from another thread (not the client's loop); waits for the reply."""
        loop = self._loop
        if loop is None or loop.is_closed():
            raise ClientError("the client is not connected: nothing to stop")
        if _in_loop(loop):
            raise ClientError("stop_threadsafe() called on the client's own loop: await stop()")
        asyncio.run_coroutine_threadsafe(self.stop(), loop).result(timeout_s)

    async def move_joints(
        self,
        goal: Sequence[float] | Mapping[int, Sequence[float]] | Mapping[str, Sequence[float]],
        *,
        group: int | str = 0,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S,
        timeout_s: float | None = None,
    ) -> MoveResult:
        """Move to joint positions (rad/m, ROS order) from wherever the robot rests now.

        ``goal`` is a list for ``group``, or ``{group: positions}`` to move several
        groups together. Waits for the robot to be at rest, plans with the model's
        limits, streams, and waits until it has settled at the goal.
        """
        if isinstance(goal, Mapping):
            groups = tuple(sorted(self.group_index(g) for g in goal))
            by_index = {self.group_index(g): v for g, v in goal.items()}
            target = tuple(v for g in groups for v in by_index[g])
        else:
            groups = (self.group_index(group),)
            target = tuple(goal)
        start = await self.current_positions(groups)
        trajectory = self.plan(
            start, target, groups=groups, speed_scale=speed_scale, accel_scale=accel_scale
        )
        return await self.execute(
            trajectory,
            groups=groups,
            on_progress=on_progress,
            goal_tolerance=goal_tolerance,
            busy_timeout_s=busy_timeout_s,
            timeout_s=timeout_s,
        )

    async def move_linear(
        self,
        pose: Sequence[float],
        *,
        group: int = 0,
        tcp_speed_mm_s: float = DEFAULT_TCP_SPEED_MM_S,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        timeout_s: float | None = None,
    ) -> MoveResult:
        """Move the selected tool's TCP in a straight line to ``pose`` = (x, y, z, rx, ry,
        rz) in base coordinates (m, rad, R = Rz·Ry·Rx), at most ``tcp_speed_mm_s`` and
        within every joint limit (scaled as :meth:`move_joints`). A line through a
        singularity, out of reach or past a joint limit is refused before anything is sent
        (:class:`PlanningError` with the joint and the numbers)."""
        from pymotoros.client.cartesian import plan_linear_move  # numpy, Pinocchio: lazily

        start = await self.current_positions(group)
        trajectory = plan_linear_move(
            self.tools.chain(group),
            start,
            pose,
            self.limits(group),
            tcp_speed_mm_s=tcp_speed_mm_s,
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
        )
        return await self.execute(
            trajectory, groups=(group,), on_progress=on_progress, timeout_s=timeout_s
        )

    async def move_relative(
        self,
        dx: float = 0.0,
        dy: float = 0.0,
        dz: float = 0.0,
        drx: float = 0.0,
        dry: float = 0.0,
        drz: float = 0.0,
        *,
        frame: Literal["base", "tool"] = "base",
        group: int = 0,
        linear: bool = True,
        tcp_speed_mm_s: float = DEFAULT_TCP_SPEED_MM_S,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
    ) -> MoveResult:
        """Move the TCP by (dx, dy, dz) m and (drx, dry, drz) rad in the ``base`` frame or
        the ``tool`` frame, in a straight line (``linear=False``: a joint move)."""
        from pymotoros.client.cartesian import relative_target
        from pymotoros.kinematics import matrix_to_pose

        start = await self.current_positions(group)
        chain = self.tools.chain(group)
        current = chain.fk(start)
        target = matrix_to_pose(relative_target(current, (dx, dy, dz, drx, dry, drz), frame))
        if linear:
            return await self.move_linear(
                target,
                group=group,
                tcp_speed_mm_s=tcp_speed_mm_s,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                on_progress=on_progress,
            )
        return await self.move_pose(
            target, group=group, speed_scale=speed_scale, accel_scale=accel_scale
        )

    async def move_pose(
        self,
        pose: Sequence[float],
        *,
        group: int = 0,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
    ) -> MoveResult:
        """A joint move to the joint values nearest the current ones that put the TCP at
        ``pose`` (base coordinates): not a straight line (see :meth:`move_linear`)."""
        start = await self.current_positions(group)
        try:
            goal = self.tools.chain(group).ik(pose, start).q
        except KinematicsError as exc:
            raise PlanningError(f"cannot reach the pose: {exc}") from None
        return await self.move_joints(
            tuple(goal.tolist()),
            group=group,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
        )

    async def read_register_outputs(
        self, table: S1cxgTable | Mapping[str, object] | str | Path, group: int = 0
    ) -> RegisterValues:
        """The S1CxG register outputs (TCP speed, Cartesian position, axis speeds and
        positions, pulses) decoded with ``table``: an :class:`S1cxgTable`, a
        ``{"330": 1, ...}`` mapping or a cell file with ``[groups.s1cxg]``."""
        if not isinstance(table, S1cxgTable):
            table = s1cxg_table(table, self.robot.groups[group], index=group)
        return await read_register_outputs(self, table, group)

    def tcp_pose(
        self,
        group: int = 0,
        *,
        frame: Literal["flange", "tool0", "tcp"] = "tcp",
        reference: Literal["base", "base_link"] = "base",
    ) -> tuple[float, float, float, float, float, float]:
        """The selected tool's TCP from the latest joint feedback: (x, y, z, rx, ry, rz) in
        m and rad, R = Rz·Ry·Rx, in base coordinates (``reference="base_link"``: the
        mounting surface). Raises ClientError before the first feedback has arrived."""
        positions = self.state.positions(group)
        if positions is None:
            raise ClientError(f"no joint feedback for group {group} yet: wait_for_state() first")
        return self.tools.chain(group).pose(positions, frame, reference)

    def named_pose(
        self, name: str, *, srdf: str | Path | None = None, group: int | str = 0
    ) -> tuple[float, ...]:
        """Joint values of a named pose: an SRDF ``group_state`` or the built-in ``home``."""
        poses: tuple[NamedPose, ...] = parse_srdf(srdf) if srdf is not None else ()
        model = self.robot.groups[self.group_index(group)]
        return find_pose(name, model, poses).positions_for(model)

    async def move_named(
        self,
        name: str,
        *,
        srdf: str | Path | None = None,
        group: int = 0,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
    ) -> MoveResult:
        """Move to a named pose (``home``, or a ``group_state`` of ``srdf``)."""
        goal = self.named_pose(name, srdf=srdf, group=group)
        return await self.move_joints(
            goal,
            group=group,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
        )


_R = TypeVar("_R")


def _expect(reply: WireMessage, cls: type[_R]) -> _R:
    """``reply`` as ``cls``, or the typed error a MOTION_REPLY refusal stands for."""
    if isinstance(reply, cls):
        return reply
    if isinstance(reply, MotoMotionReply):
        raise reply_error(reply.result, reply.subcode, reply.command)
    raise ClientError(f"unexpected reply {reply!r}, expected {cls.__name__}")


def _dh_matches(model: Sequence[object], seen: Sequence[object]) -> bool:
    return all(
        abs(getattr(m, f) - getattr(s, f)) <= DH_TOLERANCE
        for m, s in zip(model, seen, strict=False)
        for f in ("theta", "d", "a", "alpha")
    )


def _in_loop(loop: asyncio.AbstractEventLoop) -> bool:
    try:
        return asyncio.get_running_loop() is loop
    except RuntimeError:
        return False


def _groups(group: int | Sequence[int]) -> tuple[int, ...]:
    return (group,) if isinstance(group, int) else tuple(group)


async def connect(host: str = "127.0.0.1", **options: object) -> RobotClient:
    """``RobotClient(host, **options)`` connected; close it (or use ``async with``)."""
    client = RobotClient(host, **options)  # type: ignore[arg-type]
    return await client.connect()


__all__ = ["RobotClient", "connect"]
