"""The motion server (port 50240): one client, strict request/reply (reference §1.5, §3).

Requests are served one at a time in arrival order. A request the controller
cannot answer at once (START_TRAJ_MODE, START_SERVOS …) returns a
:class:`~pymotoros.controller.api.Pending`; the server awaits a future that the
pending's done-callback resolves inside a later interpolation tick, and reads
nothing else from that client meanwhile.

What MotoROS does and we do the same way: unknown types get INVALID/3003 with
group and sequence -1 and the connection is kept; types 13/15/2002/2017 close the
connection; a successful DISCONNECT and a failed GET_DH_PARAMETERS close without a
reply; a request sent with comm_type SERVICE_REPLY is processed but not answered;
IO bit/group requests are served here too (M-registers are not: 3003).

Two documented improvements: frames split across reads are reassembled (logged at
DEBUG), and the queues are cleared when the client goes away
(``controller.motion_disconnected()``).

Every reply leaves in a single ``write``: common clients read one reply per
``recv()``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import Final

from pymotoros.controller.api import MotoRosController, Outcome, Pending, PointData
from pymotoros.controller.lint import LintCode
from pymotoros.protocol.constants import (
    MAX_JOINTS,
    ByteOrder,
    CommType,
    InvalidSubcode,
    MotionCommand,
    MsgType,
    Port,
    ResultCode,
    reply_result,
    subcode_meaning,
)
from pymotoros.protocol.framing import Frame, encode
from pymotoros.protocol.messages import (
    JointTrajPtFull,
    Message,
    MotoGetDhParameters,
    MotoGetDhParametersReply,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoSelectTool,
    Ping,
    PingReply,
)
from pymotoros.protocol.sizes import Close, Reject, check_request
from pymotoros.runtime.connections import MOTION_CLIENTS
from pymotoros.runtime.io_server import handle_io_request, length_detail, log_rejection
from pymotoros.runtime.tcp import Connection, FramedService

__all__ = ["MotionServer"]

logger = logging.getLogger(__name__)

_QUIET_COMMANDS = frozenset({MotionCommand.CHECK_QUEUE_CNT, MotionCommand.CHECK_MOTION_READY})
"""Queries: a FALSE answer is information, not a refusal (logged at DEBUG)."""


_KNOWN_COMMANDS = frozenset(int(m) for m in MotionCommand)
"""MOTO_MOTION_CTRL commands MotoROS answers (§3.1); any other gets its previous reply."""


def _meaning(result: int, subcode: int) -> str:
    """Subcode text; CHECK_MOTION_READY's FALSE carries a NOT_READY subcode too (§3.1)."""
    return subcode_meaning(reply_result(result, subcode), subcode)


def _describe_command(command: int) -> str:
    try:
        return MotionCommand(command).name
    except ValueError:
        return f"unknown command {command}"


def _describe_ctrl(msg: MotoMotionCtrl) -> str:
    return f"{_describe_command(msg.command)} (group {msg.group_no}, seq {msg.sequence})"


ENCODED_REPLIES: Final = 1024
"""Distinct replies kept encoded (then forgotten all at once): bounds the memory
whatever sequence numbers a client sends."""

_NO_DATA: Final = (0.0,) * MAX_JOINTS
"""The data of every MOTO_MOTION_REPLY MotoROS sends: ten zeros."""

_new_reply: Final = tuple.__new__
"""A message tuple from values already known valid (see ``MotionServer._reply``)."""


class _CloseConnectionError(Exception):
    """Internal: the request closes the connection without a reply."""


class MotionServer(FramedService):
    """Serves MOTO_MOTION_CTRL, trajectory points, tools, DH parameters and IO to one client."""

    name = "motion"

    def __init__(self, controller: MotoRosController, order: ByteOrder) -> None:
        super().__init__(
            MOTION_CLIENTS,
            lambda: controller.has_queued_motion(),
            order,
            MotoMotionReply(-1, -1, 0, ResultCode.INVALID, InvalidSubcode.MSGSIZE),
        )
        self._controller = controller
        self._encoded: dict[MotoMotionReply, bytes] = {}
        self.requests = 0

    def on_connect(self, conn: Connection) -> None:
        c = self._controller
        c.lint.motion_opened(conn.peer, c.time_ms / 1000.0, queued=c.has_queued_motion())
        c.motion_connected()

    def lint(self, code: LintCode, conn: Connection, detail: str = "") -> None:
        c = self._controller
        c.lint.record(code, conn.peer, c.time_ms / 1000.0, detail)

    async def send(self, conn: Connection, message: Message) -> None:
        """:meth:`FramedService.send`, with each distinct MOTO_MOTION_REPLY encoded once:
        a client polling CHECK_QUEUE_CNT gets the same few replies thousands of times,
        and encoding one costs ~6 µs of Python (issue 13)."""
        if type(message) is not MotoMotionReply or message.data is not _NO_DATA:
            await super().send(conn, message)  # not one of _reply's (equal is not enough:
            return  # -0.0 == 0.0 in a key, but not on the wire)
        self.traffic.reply(message)
        data = self._encoded.get(message)
        if data is None:
            if len(self._encoded) >= ENCODED_REPLIES:
                self._encoded.clear()
            data = self._encoded[message] = encode(message, self._order)
        conn.write(data)  # through the connection: `sim --record` sees it
        await conn.writer.drain()

    def on_disconnect(self, conn: Connection) -> None:
        # Our improvement over MotoROS (§2.2): nothing keeps moving for a client that left.
        self._controller.motion_disconnected()

    # ----------------------------------------------------------- reading

    async def serve_connection(self, conn: Connection) -> None:
        async with contextlib.aclosing(self.frames(conn)) as frames:
            async for frame in frames:
                try:
                    await self._serve_frame(conn, frame)
                except _CloseConnectionError:
                    return

    async def _serve_frame(self, conn: Connection, frame: Frame) -> None:
        self.requests += 1
        verdict = check_request(frame, self._order, Port.MOTION)
        if isinstance(verdict, Close):
            # One line per connection, but a flood of connects can repeat it: the port's
            # allowance (runtime/log_limit.py).
            if self.log.allow("connections closed for their message type", logger, logging.WARNING):
                logger.warning(
                    "motion: client %s sent %s; closing the connection as MotoROS does",
                    conn.peer,
                    verdict.reason,
                )
            raise _CloseConnectionError
        if isinstance(verdict, Reject):
            log_rejection(conn, frame, verdict, self._order, Port.MOTION, logger)
            if verdict.subcode == InvalidSubcode.MSGSIZE:
                self.lint(
                    LintCode.LENGTH_MISMATCH, conn, length_detail(frame, self._order, Port.MOTION)
                )
            reply: Message = verdict.reply
        else:
            if verdict.surplus:
                self.lint(
                    LintCode.LENGTH_MISMATCH, conn, length_detail(frame, self._order, Port.MOTION)
                )
                logger.debug(
                    "motion: client %s: %d surplus bytes after type %d ignored",
                    conn.peer,
                    verdict.surplus,
                    frame.msg_type,
                )
            reply = await self._process(conn, verdict.message, frame.msg_type)
        if frame.comm_type == CommType.SERVICE_REPLY:
            # MotoROS processes such a message but sends nothing back (§1.1).
            logger.debug("motion: client %s: request sent as SERVICE_REPLY, no reply", conn.peer)
            return
        await self.send(conn, reply)

    # ----------------------------------------------------------- requests

    async def _process(self, conn: Connection, msg: Message, msg_type: int) -> Message:
        c = self._controller
        if isinstance(msg, MotoMotionCtrl):
            if msg.command not in _KNOWN_COMMANDS:
                self.lint(LintCode.UNKNOWN_COMMAND, conn, f"command {msg.command}")
                self.lint(LintCode.STALE_REPLY, conn, f"MOTO_MOTION_CTRL command {msg.command}")
            elif msg.command not in _QUIET_COMMANDS:
                c.lint.motion_reset()
            outcome = await self._resolve(c.motion_ctrl(msg.group_no, msg.command))
            if outcome.close_connection and not self.log.allow(
                "connections closed on request", logger, logging.INFO
            ):
                raise _CloseConnectionError
            if outcome.close_connection:
                logger.info(
                    "motion: client %s: %s succeeded; closing without reply",
                    conn.peer,
                    _describe_ctrl(msg),
                )
                raise _CloseConnectionError
            if not outcome.ok:  # described only when logged: most requests succeed
                quiet = msg.command in _QUIET_COMMANDS
                self._log_outcome(conn, _describe_ctrl(msg), outcome, quiet=quiet)
            return self._reply(outcome, msg.group_no, msg.sequence, msg.command)
        if isinstance(msg, JointTrajPtFull):
            point = PointData(msg.group_no, msg.valid_fields, msg.time, msg.pos, msg.vel, msg.acc)
            outcome = await self._resolve(c.trajectory_point(msg.sequence, point))
            what = f"JOINT_TRAJ_PT_FULL seq {msg.sequence} (group {msg.group_no}, t {msg.time:g} s)"
            self._log_outcome(conn, what, outcome)
            c.lint.point_answered(
                conn.peer,
                ((msg.group_no, any(msg.vel)),),
                msg.sequence,
                outcome.result,
                c.time_ms / 1000.0,
            )
            return self._reply(outcome, msg.group_no, msg.sequence, MsgType.JOINT_TRAJ_PT_FULL)
        if isinstance(msg, MotoJointTrajPtFullEx):
            points = [
                PointData(g.group_no, g.valid_fields, g.time, g.pos, g.vel, g.acc)
                for g in msg.groups
            ]
            outcome = await self._resolve(c.trajectory_point_ex(msg.sequence, points))
            groups = ",".join(str(p.group_no) for p in points)
            what = f"JOINT_TRAJ_PT_FULL_EX seq {msg.sequence} (groups {groups or 'none'})"
            self._log_outcome(conn, what, outcome)
            if msg.number_of_valid_groups <= 0:
                self.lint(
                    LintCode.STALE_REPLY, conn, f"FULL_EX with {msg.number_of_valid_groups} groups"
                )
            else:
                c.lint.point_answered(
                    conn.peer,
                    [(p.group_no, any(p.vel)) for p in points],
                    msg.sequence,
                    outcome.result,
                    c.time_ms / 1000.0,
                )
            last = points[-1].group_no if points else -1
            return self._reply(outcome, last, msg.sequence, MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX)
        if isinstance(msg, MotoSelectTool):
            outcome = c.select_tool(msg.group_no, msg.tool)
            what = f"SELECT_TOOL {msg.tool} (group {msg.group_no})"
            self._log_outcome(conn, what, outcome)
            return self._reply(outcome, msg.group_no, msg.sequence, MsgType.MOTO_SELECT_TOOL)
        if isinstance(msg, MotoGetDhParameters):
            dh = c.dh_parameters()
            if dh is None and not self.log.allow(
                "connections closed for DH parameters", logger, logging.WARNING
            ):
                raise _CloseConnectionError
            if dh is None:
                logger.warning(
                    "motion: client %s: DH parameters unavailable; closing the connection "
                    "as MotoROS does (§5.9)",
                    conn.peer,
                )
                raise _CloseConnectionError
            return MotoGetDhParametersReply.for_groups(dh)
        if isinstance(msg, Ping):
            return PingReply()
        reply = handle_io_request(c, msg, "motion", conn, logger)
        if reply is None:  # pragma: no cover - check_request answers unknown types itself
            return MotoMotionReply(-1, -1, msg_type, ResultCode.INVALID, InvalidSubcode.MSGTYPE)
        return reply

    async def _resolve(self, result: Outcome | Pending) -> Outcome:
        if isinstance(result, Outcome):
            return result
        future: asyncio.Future[Outcome] = asyncio.get_running_loop().create_future()

        def done(outcome: Outcome) -> None:
            if not future.done():
                future.set_result(outcome)

        result.add_done_callback(done)
        return await future

    @staticmethod
    def _reply(outcome: Outcome, group: int, sequence: int, command: int) -> MotoMotionReply:
        # Built without the constructor's per-field checks (10 floats and 5 ints: two
        # thirds of a CHECK_QUEUE_CNT's Python time, issue 13): group, sequence and
        # command are echoed from a decoded request, result and subcode are the
        # controller's codes, the data are zeros; pack() still range-checks every field.
        return _new_reply(
            MotoMotionReply,
            (
                group if outcome.group_no is None else outcome.group_no,
                sequence,
                command,
                int(outcome.result),
                outcome.subcode,
                _NO_DATA,
            ),
        )

    @staticmethod
    def _log_outcome(conn: Connection, what: str, outcome: Outcome, *, quiet: bool = False) -> None:
        if outcome.ok:
            return
        level = logging.DEBUG if outcome.result == ResultCode.BUSY or quiet else logging.WARNING
        # DEBUG lines are the opted-in full protocol trace; WARNINGs are the client's
        # allowance (runtime/log_limit.py).
        if (
            logger.isEnabledFor(level)
            if level == logging.DEBUG
            else conn.log.allow("refused requests", logger, level)
        ):
            logger.log(
                level,
                "motion: client %s: %s -> %s / %s%s",
                conn.peer,
                what,
                ResultCode.describe(outcome.result),
                _meaning(outcome.result, outcome.subcode),
                f": {outcome.detail}" if outcome.detail else "",
            )
