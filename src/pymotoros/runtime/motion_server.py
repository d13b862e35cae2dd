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

Fidelity (docs/fidelity.md §1): in ``exact``, the default, requests are cut from the
stream as MotoROS's receive loop cuts them (a message split across reads: 3001, then
its tail as a new message), an unknown MOTION_CTRL command and a FULL_EX with
``numberOfValidGroups`` ≤ 0 get the connection's previous reply again (four zero bytes
before the first), and the queues survive the client's going away
(``controller.motion_disconnected()``), resumed by the next connection. In ``safe``
frames are reassembled, those requests get INVALID/3006 and 3010, and the queues are
cleared when the client goes away.

Where a client lint hooks in (one method each): :meth:`MotionServer.stale_reply_seen`,
:meth:`MotionServer.unknown_command_seen`, :meth:`MotionServer.resumed_motion_seen`, and
the framing's ``fragment_seen`` / ``length_mismatch_seen`` (runtime/tcp.py).

Every reply leaves in a single ``write``: common clients read one reply per
``recv()``.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import logging
from typing import Final, Unpack

from pymotoros.controller.api import MotoRosController, Outcome, Pending, PointData
from pymotoros.controller.lint import LintCode, ResumedMotion
from pymotoros.models.fidelity import Fidelity
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
from pymotoros.protocol.sizes import Accept, Close, Reject, Verdict
from pymotoros.runtime.connections import MOTION_CLIENTS
from pymotoros.runtime.io_server import handle_io_request, log_rejection
from pymotoros.runtime.tcp import Connection, FramedService, ServiceWiring

__all__ = ["MotionServer"]

logger = logging.getLogger(__name__)

QUIET_COMMANDS = frozenset({MotionCommand.CHECK_QUEUE_CNT, MotionCommand.CHECK_MOTION_READY})
"""Queries: a FALSE answer is information, not a refusal (logged at DEBUG)."""


def _meaning(result: int, subcode: int) -> str:
    """Subcode text; CHECK_MOTION_READY's FALSE carries a NOT_READY subcode too (§3.1)."""
    return subcode_meaning(reply_result(result, subcode), subcode)


def _describe_command(command: int) -> str:
    try:
        return MotionCommand(command).name
    except ValueError:
        return f"unknown command {command}"


def _describe_type(msg_type: int) -> str:
    try:
        return MsgType(msg_type).name
    except ValueError:
        return f"type {msg_type}"


def _describe_ctrl(msg: MotoMotionCtrl) -> str:
    return f"{_describe_command(msg.command)} (group {msg.group_no}, seq {msg.sequence})"


ENCODED_REPLIES: Final = 1024
"""Distinct replies kept encoded (then forgotten all at once): bounds the memory
whatever sequence numbers a client sends."""

_NO_DATA: Final = (0.0,) * MAX_JOINTS
"""The data of every MOTO_MOTION_REPLY MotoROS sends: ten zeros."""

_new_reply: Final = tuple.__new__
"""A message tuple from values already known valid (see ``MotionServer._reply``)."""


ZERO_REPLY_BUFFER: Final = bytes(4)
"""What MotoROS sends when it builds no reply on a connection that has had none: its
reply buffer (uninitialised memory in C, taken as zeros here) is sent as
``prefix.length + 4`` bytes (MotionServer.c), and a zero prefix makes that four zero
bytes (fidelity exact; docs/fidelity.md)."""

KNOWN_COMMANDS: Final = frozenset(int(c) for c in MotionCommand)
"""The MOTO_MOTION_CTRL commands of MotoROS 1.9.12 (§1.7); any other builds no reply."""


class _Stale(enum.Enum):
    """Internal: the request builds no reply; the reply buffer is sent again."""

    STALE = "stale"


_STALE: Final = _Stale.STALE


def _describe_reply(message: Message) -> str:
    if isinstance(message, MotoMotionReply):
        return (
            f"MOTO_MOTION_REPLY command {message.command} seq {message.sequence}: "
            f"{ResultCode.describe(message.result)} / {message.subcode}"
        )
    return type(message).__name__


class _CloseConnectionError(Exception):
    """Internal: the request closes the connection without a reply."""


class MotionServer(FramedService):
    """Serves MOTO_MOTION_CTRL, trajectory points, tools, DH parameters and IO to one client."""

    name = "motion"

    def __init__(
        self,
        controller: MotoRosController,
        order: ByteOrder,
        *,
        fidelity: Fidelity | None = None,
        **wiring: Unpack[ServiceWiring],
    ) -> None:
        """``fidelity``: exact or safe (docs/fidelity.md); None takes the controller's
        (its cell's ``[motoros] fidelity``). ``wiring``: what the application gives
        (:class:`~pymotoros.runtime.tcp.ServiceWiring`; ``clients``: the same
        :class:`~pymotoros.runtime.tcp.ClientTasks` the controller was built with as its
        motion link)."""
        super().__init__(
            MOTION_CLIENTS,
            lambda: controller.has_queued_motion(),
            order,
            MotoMotionReply(-1, -1, 0, ResultCode.INVALID, InvalidSubcode.MSGSIZE),
            controller.fidelity if fidelity is None else fidelity,
            **wiring,
        )
        self._controller = controller
        self._encoded: dict[MotoMotionReply, bytes] = {}
        self._last_reply: dict[Connection, Message] = {}
        """Per connection, the last reply built (sent or not): MotoROS's reply buffer,
        which it sends again when it builds none (fidelity exact)."""
        self.requests = 0

    def on_connect(self, conn: Connection) -> None:
        c = self._controller
        resumed = c.motion_connected()  # the one source of truth (ConnectionEvents)
        if resumed is None:
            c.lint.motion_opened(conn.peer, c.time_ms / 1000.0, queued=False)
        else:
            self.resumed_motion_seen(conn, resumed)

    def resumed_motion_seen(self, conn: Connection, resumed: ResumedMotion) -> None:
        """``conn`` opened while a closed connection's increments were queued: the robot
        resumes that motion now (§2.2; the one place this is seen by a server), in
        fidelity exact from the kept queues; in safe the twin cleared them at the close
        (``resumed.cleared_s``), but a robot would resume them. The controller logs it;
        the client lint waits for the connection's first request (STOP_MOTION at once is
        no finding, docs/sim.md), the same rule in both settings."""
        c = self._controller
        c.lint.motion_opened(
            conn.peer, c.time_ms / 1000.0, queued=True, cleared_s=resumed.cleared_s
        )

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
        self._controller.lint.motion_closed(conn.peer)
        # exact: the queues stay, as on MotoROS 1.9.12; safe: cleared (§2.2, fidelity.md).
        self._controller.motion_disconnected()

    # ----------------------------------------------------------- reading

    async def serve_connection(self, conn: Connection) -> None:
        try:
            async with contextlib.aclosing(self.read_requests(conn)) as requests:
                async for frame, verdict in requests:
                    try:
                        await self._serve_frame(conn, frame, verdict)
                    except _CloseConnectionError:
                        return
        finally:
            self._last_reply.pop(conn, None)

    async def _serve_frame(self, conn: Connection, frame: Frame, verdict: Verdict) -> None:
        self.requests += 1
        if self._controller.lint.resume_pending:  # the first request after a resume
            self._first_request_seen(conn, frame, verdict)
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
            reply: Message | _Stale = verdict.reply
        else:
            if verdict.surplus:
                logger.debug(
                    "motion: client %s: %d surplus bytes after type %d ignored",
                    conn.peer,
                    verdict.surplus,
                    frame.msg_type,
                )
            reply = await self._process(conn, verdict.message, frame.msg_type)
        if reply is _STALE:
            stale = self._last_reply.get(conn)
        else:
            self._last_reply[conn] = reply
        if frame.comm_type == CommType.SERVICE_REPLY:
            # MotoROS processes such a message but sends nothing back (§1.1).
            logger.debug("motion: client %s: request sent as SERVICE_REPLY, no reply", conn.peer)
            return
        if reply is not _STALE:
            await self.send(conn, reply)
        elif stale is not None:
            await self.send(conn, stale)
        else:  # MotoROS's reply buffer before its first reply: taken as zeros
            conn.write(ZERO_REPLY_BUFFER)
            await conn.writer.drain()

    def _first_request_seen(self, conn: Connection, frame: Frame, verdict: Verdict) -> None:
        """Tell the lint what a connection opened over resumed motion sent first: STOP_MOTION
        (the right thing, no finding) or anything else (the old motion runs meanwhile)."""
        msg = verdict.message if isinstance(verdict, Accept) else None
        if isinstance(msg, MotoMotionCtrl):
            stops, what = msg.command == MotionCommand.STOP_MOTION, _describe_ctrl(msg)
        else:
            stops, what = False, _describe_type(frame.msg_type)
        self._controller.lint.motion_request(conn.peer, stops=stops, what=what)

    def stale_reply_seen(self, conn: Connection, what: str) -> _Stale:
        """``what`` builds no reply: MotoROS sends its reply buffer again, the previous
        reply of this connection (fidelity exact; the one place this is decided)."""
        previous = self._last_reply.get(conn)
        if conn.log.allow("stale replies", logger, logging.WARNING):
            logger.warning(
                "motion: client %s: %s builds no reply; sent the previous reply again (%s), "
                "as MotoROS 1.9.12 does (§3.1, §3.5): a stale reply can look like a success",
                conn.peer,
                what,
                "none yet: 4 zero bytes" if previous is None else _describe_reply(previous),
            )
        return _STALE

    def unknown_command_seen(self, conn: Connection, msg: MotoMotionCtrl) -> None:
        """A MOTO_MOTION_CTRL command MotoROS does not know (the one place this is
        decided): exact answers with a stale reply, safe with INVALID/3006. The lint
        records both findings in either setting: the robot's answer is the stale one."""
        self.lint(LintCode.UNKNOWN_COMMAND, conn, f"command {msg.command}")
        self.lint(LintCode.STALE_REPLY, conn, f"MOTO_MOTION_CTRL command {msg.command}")
        logger.debug(
            "motion: client %s: unknown MOTO_MOTION_CTRL command %d (group %d, seq %d)",
            conn.peer,
            msg.command,
            msg.group_no,
            msg.sequence,
        )

    # ----------------------------------------------------------- requests

    async def _process(self, conn: Connection, msg: Message, msg_type: int) -> Message | _Stale:
        c = self._controller
        exact = self.fidelity is Fidelity.EXACT
        if isinstance(msg, MotoMotionCtrl):
            if msg.command not in KNOWN_COMMANDS:
                self.unknown_command_seen(conn, msg)
                if exact:  # §3.1: no reply is built, the buffer is sent again
                    return self.stale_reply_seen(conn, _describe_ctrl(msg))
            elif msg.command not in QUIET_COMMANDS:
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
                quiet = msg.command in QUIET_COMMANDS
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
            n = msg.number_of_valid_groups
            if n <= 0:  # a stale reply on the robot, whatever the setting answers (§3.5)
                self.lint(LintCode.STALE_REPLY, conn, f"FULL_EX with {n} groups")
            if exact and n <= 0:  # §3.5: the reply buffer is left unset
                return self.stale_reply_seen(
                    conn,
                    f"JOINT_TRAJ_PT_FULL_EX seq {msg.sequence} with numberOfValidGroups "
                    f"{msg.number_of_valid_groups}",
                )
            points = [
                PointData(g.group_no, g.valid_fields, g.time, g.pos, g.vel, g.acc)
                for g in msg.groups
            ]
            outcome = await self._resolve(c.trajectory_point_ex(msg.sequence, points))
            groups = ",".join(str(p.group_no) for p in points)
            what = f"JOINT_TRAJ_PT_FULL_EX seq {msg.sequence} (groups {groups or 'none'})"
            self._log_outcome(conn, what, outcome)
            if n > 0:
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
