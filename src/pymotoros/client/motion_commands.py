"""The motion port's requests: MOTO_MOTION_CTRL commands, SELECT_TOOL, DH parameters, and
the plain request/reply exchange (PING and any message like it).

The motion-port part of :class:`~pymotoros.client.RobotClient`, and the
:class:`~pymotoros.client.motion_port.MotionPort` the trajectory streamer sends through.
Each request waits for its reply; a refusal becomes the typed error of
:mod:`pymotoros.client.errors` (code, meaning, remedy).
"""

from __future__ import annotations

import itertools
from typing import Final, TypeVar

from pymotoros.client.errors import ClientError, reply_error
from pymotoros.client.link import Link
from pymotoros.client.motion_port import MotionReadiness
from pymotoros.client.tools import ToolTable
from pymotoros.protocol.constants import (
    MAX_TOOL_NUMBER,
    MotionCommand,
    NotReadySubcode,
    Port,
    ResultCode,
)
from pymotoros.protocol.messages import (
    DhLink,
    MotoGetDhParameters,
    MotoGetDhParametersReply,
    MotoMotionCtrl,
    MotoMotionReply,
    MotoSelectTool,
    WireMessage,
)

SLOW_COMMAND_TIMEOUT_S: Final = 20.0
"""START_TRAJ_MODE may wait 5 s for servo power and 5 s for the job (§3.2); servo commands
wait up to 5 s (§3.1)."""

_SLOW_COMMANDS: Final = frozenset(
    {
        MotionCommand.START_TRAJ_MODE,
        MotionCommand.START_SERVOS,
        MotionCommand.STOP_SERVOS,
        MotionCommand.STOP_TRAJ_MODE,
    }
)

_R = TypeVar("_R")


def expect_reply(reply: WireMessage, cls: type[_R]) -> _R:
    """``reply`` as ``cls``, or the typed error a MOTION_REPLY refusal stands for."""
    if isinstance(reply, cls):
        return reply
    if isinstance(reply, MotoMotionReply):
        raise reply_error(reply.result, reply.subcode, reply.command)
    raise ClientError(f"unexpected reply {reply!r}, expected {cls.__name__}")


class MotionCommands:
    """Requests on the motion port, one at a time, each with a fresh sequence number."""

    def __init__(self, link: Link, tools: ToolTable, groups: int) -> None:
        self._link = link
        self._tools = tools
        self._groups = groups
        self._sequence = itertools.count(1)

    def _next_sequence(self) -> int:
        return next(self._sequence) % 2**31

    async def request_motion(
        self, message: WireMessage, *, timeout_s: float | None = None
    ) -> MotoMotionReply:
        """Send a motion-port request answered by a MOTO_MOTION_REPLY; returns it as is."""
        conn = self._link.need(Port.MOTION)
        wait = timeout_s or self._link.timeout_s
        reply = await conn.request(message, MotoMotionReply, timeout_s=wait)
        if not isinstance(reply, MotoMotionReply):
            raise ClientError(f"unexpected reply {reply!r} to {message!r}")
        return reply

    async def command(self, command: MotionCommand, group: int = 0) -> MotoMotionReply:
        """Send MOTO_MOTION_CTRL ``command``; the reply as is (slow commands wait longer)."""
        timeout = self._link.timeout_s
        wait = SLOW_COMMAND_TIMEOUT_S if command in _SLOW_COMMANDS else timeout
        message = MotoMotionCtrl(group, self._next_sequence(), int(command))
        return await self.request_motion(message, timeout_s=max(wait, timeout))

    async def command_ok(self, command: MotionCommand, group: int = 0) -> MotoMotionReply:
        """:meth:`command`, raising the typed error unless the controller answers SUCCESS."""
        reply = await self.command(command, group)
        if reply.result != ResultCode.SUCCESS:
            raise reply_error(reply.result, reply.subcode, reply.command)
        return reply

    async def check_motion_ready(self) -> MotionReadiness:
        """CHECK_MOTION_READY: ready, or the NOT_READY reason (never raises for "not ready")."""
        reply = await self.command(MotionCommand.CHECK_MOTION_READY)
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
        await self.command_ok(MotionCommand.START_TRAJ_MODE)

    async def stop_trajectory_mode(self) -> None:
        """STOP_TRAJ_MODE: end the INIT_ROS job (fails while motion is queued)."""
        await self.command_ok(MotionCommand.STOP_TRAJ_MODE)

    async def start_servos(self) -> None:
        """START_SERVOS: servo power on (the job is not started)."""
        await self.command_ok(MotionCommand.START_SERVOS)

    async def stop_servos(self) -> None:
        """STOP_SERVOS: servo power off."""
        await self.command_ok(MotionCommand.STOP_SERVOS)

    async def reset_alarm(self) -> None:
        """RESET_ALARM: reset alarms and cancel errors (not waited on by MotoROS)."""
        await self.command_ok(MotionCommand.RESET_ALARM)

    async def stop_motion(self) -> None:
        """STOP_MOTION: stop at once and clear every queue (no ramp from MotoROS)."""
        await self.command_ok(MotionCommand.STOP_MOTION)

    async def queue_count(self, group: int = 0) -> int:
        """Increments still queued for ``group`` (CHECK_QUEUE_CNT: the count is the subcode)."""
        reply = await self.command_ok(MotionCommand.CHECK_QUEUE_CNT, group)
        return reply.subcode

    async def select_tool(self, tool: int, group: int = 0) -> None:
        """MOTO_SELECT_TOOL: the tool file ``group`` moves with from its next segment on.

        The client's Cartesian operations use this tool's TCP from then on (MotoROS
        cannot report the selected tool, so the client remembers what it sent).
        """
        if not 0 <= tool <= MAX_TOOL_NUMBER:
            raise ValueError(f"tool {tool}: tool numbers are 0..{MAX_TOOL_NUMBER}")
        reply = await self.request_motion(MotoSelectTool(group, tool, self._next_sequence()))
        if reply.result != ResultCode.SUCCESS:
            raise reply_error(reply.result, reply.subcode, reply.command)
        self._tools.selected[group] = tool

    async def exchange(self, request: WireMessage, reply: type[_R]) -> _R:
        """Send ``request`` on the motion port and return its answer as ``reply`` (a
        refusal as its typed error, :func:`expect_reply`).

        This is the whole client side of a plain request/reply message: a new one is a
        method in :mod:`pymotoros.client.calls` that calls this, so adding a wire
        message takes no edit here (docs/architecture.md, "A wire message")."""
        conn = self._link.need(Port.MOTION)
        answer = await conn.request(request, reply, timeout_s=self._link.timeout_s)
        return expect_reply(answer, reply)

    async def get_dh_parameters(self) -> tuple[tuple[DhLink, ...], ...]:
        """DH parameters (theta, d, a, alpha) of each of the robot's groups."""
        reply = await self.exchange(MotoGetDhParameters(), MotoGetDhParametersReply)
        return reply.groups[: self._groups]
