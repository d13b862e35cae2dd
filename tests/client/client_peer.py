"""A small, scriptable MotoROS stand-in for the client's unit tests.

It speaks the wire through the codec on 127.0.0.1 port 0 and behaves like MotoROS
where the client depends on it (replies, echoes, BUSY, 3011/3013, NOT_READY,
CHECK_QUEUE_CNT, IO result codes, a state stream), with a trivial "robot" that
follows the accepted points exactly. Tests switch behaviours on through attributes.
The real virtual controller is exercised by the integration tests.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import math
import time
from dataclasses import dataclass, field

from pymotoros.client.robot import RobotClient
from pymotoros.models import robot_model
from pymotoros.protocol.constants import (
    ByteOrder,
    InvalidSubcode,
    IoResultCode,
    MotionCommand,
    NotReadySubcode,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import FrameDecoder, decode_request, encode
from pymotoros.protocol.messages import (
    IoErrorReply,
    JointFeedback,
    JointTrajPtFull,
    MotoGetDhParameters,
    MotoGetDhParametersReply,
    MotoJointFeedbackEx,
    MotoJointTrajPtFullEx,
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
    RobotStatus,
    UnknownMessage,
    WireMessage,
)


@dataclass
class _Point:
    time: float
    pos: list[float]
    vel: list[float]


@dataclass
class _Group:
    n: int
    ppu: list[float]
    vmax: list[float]
    pos: list[float]
    points: list[_Point] = field(default_factory=list)


def _hermite(a: _Point, b: _Point, t: float) -> list[float]:
    h = b.time - a.time
    if h <= 0:
        return list(b.pos)
    s = (t - a.time) / h
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return [
        h00 * p0 + h10 * h * v0 + h01 * p1 + h11 * h * v1
        for p0, v0, p1, v1 in zip(a.pos, a.vel, b.pos, b.vel, strict=True)
    ]


class ClientPeer:
    """Fake MotoROS: three listeners, one state stream, scriptable refusals."""

    def __init__(
        self, *, robot: str = "hc10", order: ByteOrder = ByteOrder.LITTLE, period: float = 0.01
    ) -> None:
        model = robot_model(robot)
        self.order = order
        self.period = period
        self.groups = [
            _Group(
                g.num_axes,
                [a.pulses_per_unit for a in g.axes],
                [a.max_velocity for a in g.axes],
                list(g.home),
            )
            for g in model.groups
        ]
        self.ready = False
        self.not_ready = NotReadySubcode.NOT_STARTED
        """Reason given while not ready."""
        self.enable_refusal: NotReadySubcode | None = None
        """START_TRAJ_MODE answers 5/this when set."""
        self.busy_per_point = 0
        """BUSY replies given to each point with sequence > 0 before it is accepted."""
        self.busy_forever = False
        self.silent: set[int] = set()
        """Commands / message types that get no reply (to provoke timeouts)."""
        self.wrong_echo = False
        """Answer MOTION_CTRL with a wrong sequence first (then the right reply)."""
        self.speed_scale = 1.0
        """< 1 makes the robot follow the plan slower (a safety speed limit)."""
        self.io: dict[int, int] = {}
        self.mreg: dict[int, int] = {}
        self.received: list[WireMessage] = []
        self.tool = 0
        self._t0: float | None = None
        self._busy_left = 0
        self._writers: set[asyncio.StreamWriter] = set()
        self._servers: list[asyncio.Server] = []
        self._tasks: set[asyncio.Task[None]] = set()
        self.ports: dict[Port, int] = {}

    # ------------------------------------------------------------------ lifecycle

    async def start(self) -> ClientPeer:
        for kind in (Port.MOTION, Port.STATE, Port.IO):
            server = await asyncio.start_server(
                lambda r, w, k=kind: self._accept(k, r, w), "127.0.0.1", 0
            )
            self._servers.append(server)
            self.ports[kind] = server.sockets[0].getsockname()[1]
        return self

    def _accept(
        self, kind: Port, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        self._writers.add(writer)
        handler = (
            self._state_loop(writer) if kind is Port.STATE else self._serve(kind, reader, writer)
        )
        task = asyncio.get_running_loop().create_task(handler, name=f"peer-{kind.value}")
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def drop_clients(self) -> None:
        """Close every client connection at once (the controller dies)."""
        for w in list(self._writers):
            w.close()
        for t in list(self._tasks):
            t.cancel()
        for t in list(self._tasks):
            with contextlib.suppress(asyncio.CancelledError, ConnectionError):
                await t
        for w in list(self._writers):
            with contextlib.suppress(ConnectionError, OSError):
                await w.wait_closed()
        self._writers.clear()

    async def close(self) -> None:
        for s in self._servers:
            s.close()
        await self.drop_clients()
        for s in self._servers:
            await s.wait_closed()

    # ------------------------------------------------------------------ the robot

    def _advance(self) -> None:
        if self._t0 is None:
            return
        t = (time.monotonic() - self._t0) * self.speed_scale
        for g in self.groups:
            pts = g.points
            if not pts:
                continue
            if t >= pts[-1].time:
                g.pos = list(pts[-1].pos)
                continue
            for a, b in itertools.pairwise(pts):
                if a.time <= t < b.time:
                    g.pos = _hermite(a, b, t)
                    break

    def remaining(self) -> float:
        if self._t0 is None:
            return 0.0
        end = max((g.points[-1].time for g in self.groups if g.points), default=0.0)
        return max(0.0, end - (time.monotonic() - self._t0) * self.speed_scale)

    def stop(self) -> None:
        self._advance()
        self._t0 = None
        for g in self.groups:
            g.points.clear()

    def status(self) -> RobotStatus:
        moving = self.remaining() > 0
        return RobotStatus(1, 0, 0, 0, int(moving), 2, int(self.ready))

    async def _state_loop(self, writer: asyncio.StreamWriter) -> None:
        with contextlib.suppress(ConnectionError, OSError):
            while True:
                self._advance()
                fbs = [
                    JointFeedback.for_joints(i, g.pos, [0.0] * g.n)
                    for i, g in enumerate(self.groups)
                ]
                for fb in fbs:
                    writer.write(encode(fb, self.order))
                if len(fbs) > 1:
                    writer.write(encode(MotoJointFeedbackEx.for_groups(fbs), self.order))
                writer.write(encode(self.status(), self.order))
                await writer.drain()
                await asyncio.sleep(self.period)

    # ------------------------------------------------------------------ requests

    async def _serve(
        self, kind: Port, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        decoder = FrameDecoder(self.order)
        with contextlib.suppress(ConnectionError, OSError):
            while data := await reader.read(4096):
                decoder.feed(data)
                for frame in decoder.frames():
                    msg = decode_request(frame, self.order, kind)
                    self.received.append(msg)
                    for reply in self._answer(kind, msg):
                        writer.write(encode(reply, self.order))
                    await writer.drain()

    def _reply(self, msg: WireMessage, result: int, subcode: int = 0) -> MotoMotionReply:
        if isinstance(msg, MotoMotionCtrl):
            return MotoMotionReply(msg.group_no, msg.sequence, msg.command, result, subcode)
        if isinstance(msg, JointTrajPtFull):
            return MotoMotionReply(msg.group_no, msg.sequence, 14, result, subcode)
        if isinstance(msg, MotoJointTrajPtFullEx):
            return MotoMotionReply(msg.groups[-1].group_no, msg.sequence, 2016, result, subcode)
        if isinstance(msg, MotoSelectTool):
            return MotoMotionReply(msg.group_no, msg.sequence, 2018, result, subcode)
        mtype = msg.msg_type if isinstance(msg, UnknownMessage) else int(msg.MSG_TYPE)
        return MotoMotionReply(-1, -1, mtype, result, subcode)

    def _answer(self, kind: Port, msg: WireMessage) -> list[WireMessage]:
        key = (
            msg.command
            if isinstance(msg, MotoMotionCtrl)
            else (msg.msg_type if isinstance(msg, UnknownMessage) else int(msg.MSG_TYPE))
        )
        if key in self.silent:
            return []
        if isinstance(msg, MotoMotionCtrl):
            reply = self._ctrl(msg)
            if self.wrong_echo:
                stale = MotoMotionReply(reply.group_no, reply.sequence + 1000, reply.command, 0, 0)
                return [stale, reply]
            return [reply]
        if isinstance(msg, (JointTrajPtFull, MotoJointTrajPtFullEx)):
            return [self._point(msg)]
        if isinstance(msg, MotoSelectTool):
            if not 0 <= msg.tool <= 63:
                return [self._reply(msg, ResultCode.INVALID, InvalidSubcode.DATA_TOOLNO)]
            self.tool = msg.tool
            return [self._reply(msg, ResultCode.SUCCESS)]
        if isinstance(msg, Ping):
            return [PingReply()]
        if isinstance(msg, MotoGetDhParameters):
            return [MotoGetDhParametersReply.for_groups([[(0.0, 0.1, 0.2, 0.3)]])]
        io = self._io(msg)
        if io is not None:
            return [io]
        if kind is Port.IO:
            return [IoErrorReply(ResultCode.INVALID, InvalidSubcode.MSGTYPE)]
        return [self._reply(msg, ResultCode.INVALID, InvalidSubcode.MSGTYPE)]

    def _ctrl(self, msg: MotoMotionCtrl) -> MotoMotionReply:
        c = msg.command
        if c == MotionCommand.CHECK_MOTION_READY:
            if self.ready:
                return self._reply(msg, ResultCode.SUCCESS)
            return self._reply(msg, ResultCode.FALSE, self.not_ready)
        if c == MotionCommand.START_TRAJ_MODE:
            if self.enable_refusal is not None:
                return self._reply(msg, ResultCode.NOT_READY, self.enable_refusal)
            self.ready = True
            return self._reply(msg, ResultCode.SUCCESS)
        if c == MotionCommand.STOP_TRAJ_MODE:
            if self.remaining() > 0:
                return self._reply(msg, ResultCode.FAILURE)
            self.ready = False
            self.not_ready = NotReadySubcode.NOT_STARTED
            return self._reply(msg, ResultCode.SUCCESS)
        if c == MotionCommand.CHECK_QUEUE_CNT:
            if not 0 <= msg.group_no < len(self.groups):
                return self._reply(msg, ResultCode.FAILURE, -1)
            return self._reply(msg, ResultCode.SUCCESS, math.ceil(self.remaining() / 0.004))
        if c == MotionCommand.STOP_MOTION:
            self.stop()
            return self._reply(msg, ResultCode.SUCCESS)
        if c in (MotionCommand.START_SERVOS, MotionCommand.STOP_SERVOS, MotionCommand.RESET_ALARM):
            return self._reply(msg, ResultCode.SUCCESS)
        return self._reply(msg, ResultCode.INVALID, InvalidSubcode.COMMAND)

    def _point(self, msg: JointTrajPtFull | MotoJointTrajPtFullEx) -> MotoMotionReply:
        if not self.ready:
            return self._reply(msg, ResultCode.NOT_READY, self.not_ready)
        if isinstance(msg, JointTrajPtFull):
            records = [(msg.group_no, msg.time, msg.pos, msg.vel)]
        else:
            records = [(r.group_no, r.time, r.pos, r.vel) for r in msg.groups]
        seq = msg.sequence
        if seq < 0:
            return self._reply(msg, ResultCode.INVALID, InvalidSubcode.SEQUENCE)
        if seq > 0:
            if self.busy_forever:
                return self._reply(msg, ResultCode.BUSY)
            if self._busy_left > 0:
                self._busy_left -= 1
                return self._reply(msg, ResultCode.BUSY)
            self._busy_left = self.busy_per_point
        for group_no, _t, pos, vel in records:
            if not 0 <= group_no < len(self.groups):
                return self._reply(msg, ResultCode.INVALID, InvalidSubcode.GROUPNO)
            g = self.groups[group_no]
            for i in range(g.n):
                if seq == 0:
                    self._advance()
                    if abs(math.trunc(pos[i] * g.ppu[i]) - math.trunc(g.pos[i] * g.ppu[i])) > 30:
                        return self._reply(msg, ResultCode.INVALID, InvalidSubcode.DATA_START_POS)
                if math.trunc(abs(vel[i])) > g.vmax[i]:
                    return self._reply(msg, ResultCode.INVALID, InvalidSubcode.DATA_SPEED)
        for group_no, t, pos, vel in records:
            g = self.groups[group_no]
            point = _Point(t, list(pos[: g.n]), list(vel[: g.n]))
            if seq == 0:
                self.stop()
                g.points = [point]
            else:
                g.points.append(point)
        if seq == 1:
            self._t0 = time.monotonic()
        return self._reply(msg, ResultCode.SUCCESS)

    def _io(self, msg: WireMessage) -> WireMessage | None:
        if isinstance(msg, MotoReadIoBit):
            if msg.io_address % 10 > 7:
                return MotoReadIoBitReply(0, IoResultCode.READ_ADDRESS_INVALID)
            return MotoReadIoBitReply(self.io.get(msg.io_address, 0), 0)
        if isinstance(msg, MotoWriteIoBit):
            if msg.io_value > 1:
                return MotoWriteIoBitReply(IoResultCode.WRITE_VALUE_INVALID)
            if not 10010 <= msg.io_address <= 15127:
                return MotoWriteIoBitReply(IoResultCode.WRITE_ADDRESS_INVALID)
            self.io[msg.io_address] = msg.io_value
            return MotoWriteIoBitReply(0)
        if isinstance(msg, MotoReadIoGroup):
            value = sum(self.io.get(msg.io_address * 10 + k, 0) << k for k in range(8))
            return MotoReadIoGroupReply(value, 0)
        if isinstance(msg, MotoWriteIoGroup):
            for k in range(8):
                self.io[msg.io_address * 10 + k] = (msg.io_value >> k) & 1
            return MotoWriteIoGroupReply(0)
        if isinstance(msg, MotoReadMRegister):
            n = msg.register_number % 1_000_000
            return MotoReadMRegisterReply(self.mreg.get(n, 0), 0)
        if isinstance(msg, MotoWriteMRegister):
            n = msg.register_number % 1_000_000
            if n >= 560:
                return MotoWriteMRegisterReply(IoResultCode.WRITE_ADDRESS_INVALID)
            self.mreg[n] = msg.value
            return MotoWriteMRegisterReply(0)
        return None


def client_for(peer: ClientPeer, **options: object) -> RobotClient:
    """A client (not connected yet) for ``peer``'s ports."""
    return RobotClient(
        "127.0.0.1",
        motion_port=peer.ports[Port.MOTION],
        state_port=peer.ports[Port.STATE],
        io_port=peer.ports[Port.IO],
        **options,  # type: ignore[arg-type]
    )


__all__ = ["ClientPeer", "client_for"]
