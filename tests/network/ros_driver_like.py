"""A stand-in for the ROS driver (``motoman_driver`` on ROS 1), for the reconnect tests.

**This is not the driver.** No ROS installation can run here, so this module re-enacts,
in asyncio, the parts of ``ros-industrial/motoman`` (``motoman_driver``) and of
``ros-industrial/industrial_core`` (``simple_message``) that decide what happens on the
wire when a connection to MotoROS fails. It was written from reading their sources; each
behaviour below names the file it follows. Nothing else of the driver is modelled (no
action server, no joint-name mapping, no velocity validation, one motion group).

Motion side (``motoman_driver/src/joint_trajectory_streamer.cpp``,
``MotomanJointTrajectoryStreamer``):

* a trajectory goal first asks CHECK_MOTION_READY; unless the answer is TRUE the
  trajectory is aborted and nothing else is sent: re-arming (START_TRAJ_MODE) is the
  ``robot_enable`` service's job, called by the application (:meth:`MotionInterface.enable`),
  never automatic (the automatic START_TRAJ_MODE was removed by motoman PR #155);
* the goal is rejected unless its first point is within 1e-4 rad of the current joint
  state (``is_valid``);
* its points are sent one at a time as JOINT_TRAJ_PT_FULL, sequence = index in the
  trajectory (0, 1, 2, …), each waiting for its reply; SUCCESS moves to the next point,
  BUSY sends the same point again on the next turn, anything else aborts the trajectory
  (state IDLE);
* the streaming loop sleeps 5 ms per turn (10 ms more while IDLE); a point whose send or
  receive fails is **not** counted as sent ("will try again"); on the next turn the
  connection is seen down and up to 5 reconnect attempts follow, each a connect then a
  250 ms wait; after a successful one the loop **carries on streaming the same
  trajectory at the same point** (same sequence number, no CHECK_MOTION_READY, no
  START_TRAJ_MODE); after 5 failed ones the trajectory is dropped (IDLE) and the next
  goal must bring the connection back;
* MOTO_MOTION_CTRL requests carry the group (``robot_id``) and sequence 0.

Connection (``simple_message/src/socket/tcp_client.cpp``, ``simple_socket.cpp``,
``smpl_msg_connection.cpp``):

* ``makeConnect`` refuses while connected, otherwise closes the stale socket and opens a
  fresh one (industrial_core PR #263; before it a dropped TcpClient could not reconnect);
* any failed send, a receive error or a receive of 0 bytes marks the connection down;
  a send while down fails at once ("Not connected");
* a reply is read as a 4-byte length then that many bytes, **with no timeout**: the
  socket is polled every second, forever, so a peer that vanishes without FIN or RST
  blocks the driver until the operating system gives up on the connection.

State side (``motoman_driver/src/industrial_robot_client/robot_state_interface.cpp``,
``simple_message/src/message_manager.cpp``, ``simple_comms_fault_handler.cpp``): one
connect at start-up to port 50241 (``robot_state_node.cpp``), then a loop: if down, one
connect attempt; receive one message and hand it to its handler (JOINT_FEEDBACK,
ROBOT_STATUS); a failed receive is only logged; after a turn that ends disconnected the
loop sleeps :data:`STATE_RECONNECT_DELAY_S` (5 s, a constant in ``MessageManager::spin``)
before the next attempt. Tests pass a scaled-down delay.

The driver's own sleeps are the behaviour under test here, so this module sleeps; the
tests never sleep to wait for an outcome, they wait (bounded) on :meth:`Recorder.wait_until`.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import logging
import socket
import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Final

from pymotoros.client.planning import JointTrajectory
from pymotoros.protocol import (
    ByteOrder,
    FrameDecoder,
    MotionCommand,
    Port,
    ResultCode,
    encode,
    subcode_meaning,
)
from pymotoros.protocol.messages import (
    JointFeedback,
    JointTrajPtFull,
    MotoMotionCtrl,
    MotoMotionReply,
    RobotStatus,
    WireMessage,
)

logger = logging.getLogger(__name__)

# ---------------------------------------------------------------- the driver's constants

LOOP_PERIOD_S: Final = 0.005
"""streamingThread: sleep at the top of every turn (joint_trajectory_streamer.cpp)."""

IDLE_EXTRA_S: Final = 0.010
"""streamingThread: the extra sleep of a turn spent IDLE."""

CONNECT_SETTLE_S: Final = 0.250
"""streamingThread: wait after each makeConnect before asking isConnected."""

RECONNECT_ATTEMPTS: Final = 5
"""streamingThread: connectRetryCount set when a STREAMING turn finds the connection down."""

STARTUP_ATTEMPTS: Final = 1
"""streamingThread: connectRetryCount's initial value (one connect at start-up)."""

START_POSITION_TOLERANCE: Final = 1e-4
"""MotomanJointTrajectoryStreamer::is_valid: start_pos_tol_ (rad)."""

STATE_RECONNECT_DELAY_S: Final = 5.0
"""MessageManager::spin: sleep after a turn that ends disconnected (mySleep(5))."""

SOCKET_POLL_S: Final = 1.0
"""SimpleSocket::SOCKET_POLL_TO: receive polls this long, then polls again (no timeout)."""

MAX_TURNS: Final = 100_000
"""Not the driver's: a bound on each loop of the stand-in (about 8 min of streaming turns)."""


class TransferState(enum.Enum):
    """TransferStates of the streamer (only the two the Motoman streamer uses)."""

    IDLE = "idle"
    STREAMING = "streaming"


@dataclass(frozen=True, slots=True)
class Exchange:
    """One request the stand-in sent and the reply it got (None: send or receive failed)."""

    connection: int
    """Which successful connect carried it (0 for the first)."""
    request: WireMessage
    reply: WireMessage | None
    at: float


@dataclass
class Recorder:
    """What a stand-in did, in order, and a bounded wait on it."""

    notes: list[str] = field(default_factory=list)
    """The driver's log lines (paraphrased), for the test's failure messages."""
    _changed: asyncio.Event = field(default_factory=asyncio.Event)

    def note(self, text: str) -> None:
        logger.debug("ros-driver-like: %s", text)
        self.notes.append(text)
        self.changed()

    def changed(self) -> None:
        self._changed.set()
        self._changed = asyncio.Event()

    async def wait_until(self, predicate: Callable[[], bool], timeout_s: float = 10.0) -> None:
        """Wait (bounded) until ``predicate()`` holds; re-checked after every event."""
        async with asyncio.timeout(timeout_s):
            while not predicate():
                event = self._changed
                await event.wait()


class SimpleMessageConnection:
    """simple_message's TcpClient as the driver uses it: connected flag, no receive timeout."""

    def __init__(self, host: str, port: int, order: ByteOrder, recorder: Recorder) -> None:
        self.host = host
        self.port = port
        self.order = order
        self.recorder = recorder
        self.connected = False
        self.connections = 0
        """Successful connects so far; the current one is number ``connections - 1``."""
        self.attempts: list[tuple[float, bool]] = []
        """Every makeConnect that tried: (monotonic time, succeeded)."""
        self._reader: asyncio.StreamReader | None = None
        self._writer: asyncio.StreamWriter | None = None

    async def make_connect(self) -> bool:
        """TcpClient::makeConnect: never while connected; a fresh socket each time."""
        if self.connected:
            self.recorder.note("tried to connect when socket already in connected state")
            return False
        self._close_stale()
        try:
            reader, writer = await asyncio.open_connection(self.host, self.port)
        except OSError as exc:
            self.attempts.append((time.monotonic(), False))
            self.recorder.note(f"failed to connect to {self.host}:{self.port}: {exc}")
            return False
        sock = writer.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._reader, self._writer = reader, writer
        self.connected = True
        self.connections += 1
        self.attempts.append((time.monotonic(), True))
        self.recorder.note(
            f"connected to {self.host}:{self.port} (connection {self.connections - 1})"
        )
        return True

    def _close_stale(self) -> None:
        if self._writer is not None:
            self._writer.close()
        self._reader = self._writer = None

    async def send(self, message: WireMessage) -> bool:
        """SimpleSocket::sendBytes: any failure, or not being connected, marks it down."""
        if not self.connected or self._writer is None:
            self.recorder.note("not connected, bytes not sent")
            self.connected = False
            return False
        try:
            self._writer.write(encode(message, self.order))
            await self._writer.drain()
        except OSError as exc:
            self.recorder.note(f"socket sendBytes failed: {exc}")
            self.connected = False
            return False
        return True

    async def receive(self, port: Port) -> WireMessage | None:
        """SmplMsgConnection::receiveMsg: length, then the message; waits as long as it takes.

        The driver polls every :data:`SOCKET_POLL_S` and polls again on a timeout, so
        it never gives up on its own; awaiting the bytes with no timeout is the same.
        """
        if not self.connected or self._reader is None:
            self.recorder.note("not connected, bytes not received")
            self.connected = False
            return None
        try:
            prefix = await self._reader.readexactly(4)
            (length,) = struct.unpack(f"{self.order.value}i", prefix)
            rest = await self._reader.readexactly(length)
        except (OSError, asyncio.IncompleteReadError) as exc:
            self.recorder.note(f"receive failed: {exc!r}")
            self.connected = False
            return None
        decoder = FrameDecoder(self.order)
        decoder.feed(prefix + rest)
        return decoder.next_reply(port)

    def close(self) -> None:
        self._close_stale()
        self.connected = False


async def cancel_and_wait(task: asyncio.Task[None] | None) -> None:
    """Cancel ``task`` (if there is one) and wait until it has ended."""
    if task is not None:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


class MotionInterface:
    """MotomanJointTrajectoryStreamer on port 50240: trajectories, robot_enable, its loop."""

    def __init__(
        self,
        host: str,
        port: int,
        *,
        robot_id: int = 0,
        order: ByteOrder = ByteOrder.LITTLE,
        joint_state: Callable[[], Sequence[float] | None] | None = None,
    ) -> None:
        self.recorder = Recorder()
        self.conn = SimpleMessageConnection(host, port, order, self.recorder)
        self.robot_id = robot_id
        self.joint_state = joint_state
        """The current joint positions (the joint_states topic), for the start check."""
        self.state = TransferState.IDLE
        self.current_traj: list[JointTrajPtFull] = []
        self.current_point = 0
        self.exchanges: list[Exchange] = []
        self.aborted: str | None = None
        """Why the last trajectory was dropped, if it was."""
        self._conx_lock = asyncio.Lock()  # smpl_msg_conx_mutex_
        self._mutex = asyncio.Lock()  # JointTrajectoryStreamer::mutex_
        self._task: asyncio.Task[None] | None = None

    # ------------------------------------------------------------------ life cycle

    async def __aenter__(self) -> MotionInterface:
        self._task = asyncio.create_task(self._streaming_thread())
        return self

    async def __aexit__(self, *exc: object) -> None:
        await cancel_and_wait(self._task)
        self.conn.close()

    # ------------------------------------------------------------------ requests

    async def _send_and_receive(self, request: WireMessage) -> WireMessage | None:
        """SmplMsgConnection::sendAndReceiveMsg, recorded with the connection it used."""
        connection = self.conn.connections - 1
        reply: WireMessage | None = None
        if await self.conn.send(request):
            reply = await self.conn.receive(Port.MOTION)
        self.exchanges.append(Exchange(connection, request, reply, time.monotonic()))
        self.recorder.changed()
        return reply

    async def _motion_ctrl(self, command: MotionCommand) -> MotoMotionReply | None:
        """MotomanMotionCtrl::sendAndReceive: group = robot_id, sequence 0."""
        async with self._conx_lock:
            reply = await self._send_and_receive(MotoMotionCtrl(self.robot_id, 0, int(command)))
        if not isinstance(reply, MotoMotionReply):
            self.recorder.note(f"failed to send {command.name}")
            return None
        return reply

    async def controller_ready(self) -> bool:
        """CHECK_MOTION_READY answered TRUE."""
        reply = await self._motion_ctrl(MotionCommand.CHECK_MOTION_READY)
        return reply is not None and reply.result == ResultCode.TRUE

    async def enable(self) -> bool:
        """The robot_enable service: START_TRAJ_MODE, success only on SUCCESS."""
        reply = await self._motion_ctrl(MotionCommand.START_TRAJ_MODE)
        if reply is None or reply.result != ResultCode.SUCCESS:
            detail = "no reply" if reply is None else subcode_meaning(reply.result, reply.subcode)
            self.recorder.note(f"robot was NOT enabled: {detail}")
            return False
        return True

    async def stop(self) -> bool:
        """trajectoryStop: IDLE, then STOP_MOTION."""
        self.state = TransferState.IDLE
        reply = await self._motion_ctrl(MotionCommand.STOP_MOTION)
        return reply is not None and reply.result == ResultCode.SUCCESS

    # ------------------------------------------------------------------ trajectories

    async def execute(self, points: Sequence[JointTrajPtFull]) -> bool:
        """jointTrajectoryCB: a goal while streaming stops the robot; else validate and send."""
        if self.state is not TransferState.IDLE:
            self.recorder.note("trajectory splicing not implemented, stopping current motion")
            async with self._mutex:
                await self.stop()
            return False
        if not points:
            return False
        problem = self._invalid(points)
        if problem is not None:
            self.recorder.note(f"validation failed: {problem}")
            return False
        return await self._send_to_robot(points)

    def _invalid(self, points: Sequence[JointTrajPtFull]) -> str | None:
        """MotomanJointTrajectoryStreamer::is_valid, the start-position part."""
        if self.joint_state is None:
            return None
        current = self.joint_state()
        if current is None:
            return "can't get current robot position"
        start = points[0].pos[: len(current)]
        if any(abs(a - b) > START_POSITION_TOLERANCE for a, b in zip(start, current, strict=True)):
            return "trajectory doesn't start at current position"
        return None

    async def _send_to_robot(self, points: Sequence[JointTrajPtFull]) -> bool:
        """MotomanJointTrajectoryStreamer::send_to_robot: CHECK_MOTION_READY, then stream."""
        if not await self.controller_ready():
            self.aborted = "not motion-ready: call robot_enable and retry"
            self.recorder.note(f"trajectory execution ABORTED: {self.aborted}")
            return False
        async with self._mutex:
            self.current_traj = list(points)
            self.current_point = 0
            self.aborted = None
            self.state = TransferState.STREAMING
        self.recorder.changed()
        return True

    # ------------------------------------------------------------------ the loop

    async def _streaming_thread(self) -> None:
        """MotomanJointTrajectoryStreamer::streamingThread, one turn per iteration."""
        retries = STARTUP_ATTEMPTS
        for _turn in range(MAX_TURNS):
            await asyncio.sleep(LOOP_PERIOD_S)
            if retries > 0:
                retries -= 1
                async with self._conx_lock:
                    await self.conn.make_connect()
                await asyncio.sleep(CONNECT_SETTLE_S)
                if self.conn.connected:
                    retries = 0
                elif retries <= 0:
                    self.recorder.note("timeout connecting to robot controller")
                    self.state = TransferState.IDLE
                self.recorder.changed()
                continue
            async with self._mutex:
                if self.state is TransferState.IDLE:
                    await asyncio.sleep(IDLE_EXTRA_S)
                    continue
                if self.current_point >= len(self.current_traj):
                    self.recorder.note("trajectory streaming complete, setting state to IDLE")
                    self.state = TransferState.IDLE
                    continue
                if not self.conn.connected:
                    self.recorder.note("robot disconnected, attempting reconnect")
                    retries = RECONNECT_ATTEMPTS
                    continue
                await self._stream_one()
        raise RuntimeError(f"the streaming loop ran {MAX_TURNS} turns: a test forgot to end it")

    async def _stream_one(self) -> None:
        point = self.current_traj[self.current_point]
        async with self._conx_lock:
            reply = await self._send_and_receive(point)
        if reply is None:
            self.recorder.note(f"failed sent joint point {point.sequence}, will try again")
        elif not isinstance(reply, MotoMotionReply):
            self._abort(f"unable to parse the reply to point {point.sequence}: {reply!r}")
        elif reply.result == ResultCode.SUCCESS:
            self.current_point += 1
        elif reply.result != ResultCode.BUSY:  # BUSY: the same point on the next turn
            meaning = subcode_meaning(reply.result, reply.subcode)
            self._abort(f"failed to send point {point.sequence}: {meaning}")

    def _abort(self, why: str) -> None:
        self.aborted = why
        self.state = TransferState.IDLE
        self.recorder.note(f"aborting trajectory: {why}")

    # ------------------------------------------------------------------ for the tests

    def points_on(self, connection: int) -> list[tuple[int, int | None]]:
        """(sequence, result) of every point sent on ``connection``; result None: no reply."""
        return [
            (e.request.sequence, e.reply.result if isinstance(e.reply, MotoMotionReply) else None)
            for e in self.exchanges
            if e.connection == connection and isinstance(e.request, JointTrajPtFull)
        ]


class StateInterface:
    """RobotStateInterface + MessageManager on port 50241: joint_states and robot_status."""

    def __init__(
        self,
        host: str,
        port: int,
        *,
        order: ByteOrder = ByteOrder.LITTLE,
        reconnect_delay_s: float = STATE_RECONNECT_DELAY_S,
        joints: int = 6,
    ) -> None:
        self.recorder = Recorder()
        self.conn = SimpleMessageConnection(host, port, order, self.recorder)
        self.reconnect_delay_s = reconnect_delay_s
        self.joints = joints
        self.positions: tuple[float, ...] | None = None
        self.status: RobotStatus | None = None
        self.feedback_per_connection: dict[int, int] = {}
        """JOINT_FEEDBACK messages received on each connection."""
        self.lost_at: list[float] = []
        """When each receive failed (monotonic), in order."""
        self._task: asyncio.Task[None] | None = None

    async def __aenter__(self) -> StateInterface:
        await self.conn.make_connect()  # RobotStateInterface::init
        self._task = asyncio.create_task(self._spin())
        return self

    async def __aexit__(self, *exc: object) -> None:
        await cancel_and_wait(self._task)
        self.conn.close()

    def joint_state(self) -> tuple[float, ...] | None:
        return self.positions

    async def _spin(self) -> None:
        """MessageManager::spin: a turn, then 5 s of sleep while disconnected."""
        for _turn in range(MAX_TURNS):
            await self._spin_once()
            if not self.conn.connected:
                await asyncio.sleep(self.reconnect_delay_s)
        raise RuntimeError(f"the state loop ran {MAX_TURNS} turns: a test forgot to end it")

    async def _spin_once(self) -> None:
        """MessageManager::spinOnce: reconnect if down (one attempt), then one message."""
        if not self.conn.connected:
            self.recorder.note("connection failed, attempting reconnect")
            await self.conn.make_connect()
        message = await self.conn.receive(Port.STATE)
        if message is None:
            self.lost_at.append(time.monotonic())
            self.recorder.note("failed to receive incoming message (send failure, no callback)")
            return
        if isinstance(message, JointFeedback):
            connection = self.conn.connections - 1
            self.feedback_per_connection[connection] = (
                self.feedback_per_connection.get(connection, 0) + 1
            )
            self.positions = tuple(message.pos[: self.joints])
        elif isinstance(message, RobotStatus):
            self.status = message
        self.recorder.changed()


def trajectory_points(plan: JointTrajectory, *, robot_id: int = 0) -> list[JointTrajPtFull]:
    """create_message for each planned point: sequence = its index, time from the start,
    positions, velocities and (when planned) accelerations."""
    return [
        JointTrajPtFull.for_joints(
            robot_id, i, p.time, p.positions, p.velocities, p.accelerations or None
        )
        for i, p in enumerate(plan.points)
    ]
