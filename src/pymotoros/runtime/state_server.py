"""The state server (port 50241): the feedback and status stream, up to four clients.

Every :data:`STATE_PERIOD_S` the broadcaster builds one *cycle* from the
controller, as MotoROS's state task does (§2.3–2.6): a JOINT_FEEDBACK per group,
then a JOINT_FEEDBACK_EX when the controller has two or more groups, then a
ROBOT_STATUS. The frames are encoded once and offered to every client.

Each client has its own sender task and a one-cycle *latest-value slot*: a new
cycle replaces one the client has not started sending yet (counted as dropped), so
a slow reader gets the freshest state, never a backlog, and never slows the
broadcaster or the interpolation loop. Every message goes out in its own
``write``, :data:`STATE_MESSAGE_GAP_S` after the previous one of its cycle, because
common clients read one message per ``recv()`` (clients.md §1.3).

MotoROS never reads a state socket; we read and discard only to notice a client
that went away.
"""

from __future__ import annotations

import asyncio
import logging
import socket
from typing import Final

from pymotoros.controller.api import MotoRosController
from pymotoros.protocol.constants import ByteOrder
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import JointFeedback, MotoJointFeedbackEx, RobotStatus
from pymotoros.runtime.clock import Clock
from pymotoros.runtime.connections import STATE_CLIENTS
from pymotoros.runtime.tcp import READ_CHUNK, Connection, TcpService

__all__ = ["STATE_MESSAGE_GAP_S", "STATE_PERIOD_S", "StateServer"]

logger = logging.getLogger(__name__)

STATE_PERIOD_S: Final = 0.025
"""STATE_UPDATE_MIN_PERIOD: MotoROS's state task sleeps 25 ms per cycle (§2.3, §5.1)."""

STATE_MESSAGE_GAP_S: Final = 0.001
"""Spacing of the messages of one cycle, as a real controller's separate sends arrive."""

STATE_SEND_BUFFER: Final = 4096
"""SO_SNDBUF of state sockets (Linux doubles it): a few cycles (a 4-group cycle is 1.2 kB)."""

STATE_WRITE_HIGH_WATER: Final = 4096
"""Transport buffer above which a client's sender waits (and its cycles get replaced)."""


class _StateClient:
    """One state connection's latest-value slot."""

    __slots__ = ("conn", "dropped", "latest", "sent", "wakeup")

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.latest: tuple[bytes, ...] | None = None
        self.wakeup = asyncio.Event()
        self.dropped = 0
        self.sent = 0

    def offer(self, cycle: tuple[bytes, ...]) -> None:
        if self.latest is not None:
            self.dropped += 1
        self.latest = cycle
        self.wakeup.set()


class StateServer(TcpService):
    """Streams feedback and status to up to four clients."""

    name = "state"

    def __init__(
        self,
        controller: MotoRosController,
        order: ByteOrder,
        clock: Clock,
        *,
        period: float = STATE_PERIOD_S,
        message_gap: float = STATE_MESSAGE_GAP_S,
    ) -> None:
        super().__init__(STATE_CLIENTS, lambda: controller.has_queued_motion())
        self._controller = controller
        self._order = order
        self._clock = clock
        self.period = period
        self.message_gap = message_gap
        self._clients: dict[Connection, _StateClient] = {}
        self.cycles = 0

    # ----------------------------------------------------------- cycles

    def build_cycle(self) -> tuple[bytes, ...]:
        """The frames of one state cycle, encoded: feedback per group, EX if ≥ 2, status."""
        c = self._controller
        order = self._order
        feedback = []
        for g in range(c.num_groups):
            data = c.joint_feedback(g)
            feedback.append(
                JointFeedback(data.group_no, data.valid_fields, 0.0, data.pos, data.vel)
            )
        frames = [encode(fb, order) for fb in feedback]
        if len(feedback) >= 2:
            frames.append(encode(MotoJointFeedbackEx.for_groups(feedback), order))
        s = c.robot_status()
        status = RobotStatus(
            s.drives_powered,
            s.e_stopped,
            s.error_code,
            s.in_error,
            s.in_motion,
            s.mode,
            s.motion_possible,
        )
        frames.append(encode(status, order))
        return tuple(frames)

    async def broadcast(self) -> None:
        """Offer a fresh cycle to every client every period, until cancelled."""
        clock = self._clock
        deadline = clock.now()
        while True:
            if self._clients:
                cycle = self.build_cycle()
                self.cycles += 1
                for client in self._clients.values():
                    client.offer(cycle)
            deadline += self.period
            now = clock.now()
            if now - deadline > self.period:
                deadline = now  # stalled: restart the rhythm instead of bursting
            await clock.sleep_until(deadline)

    # ----------------------------------------------------------- connections

    def on_connect(self, conn: Connection) -> None:
        sock = conn.writer.get_extra_info("socket")
        if sock is not None:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, STATE_SEND_BUFFER)
        conn.writer.transport.set_write_buffer_limits(high=STATE_WRITE_HIGH_WATER)
        self._clients[conn] = _StateClient(conn)
        self._controller.state_clients_changed(self.clients)

    def on_disconnect(self, conn: Connection) -> None:
        self._controller.state_clients_changed(self.clients)

    async def serve_connection(self, conn: Connection) -> None:
        client = self._clients[conn]
        try:
            async with asyncio.TaskGroup() as tg:
                sender = tg.create_task(self._send_loop(client), name=f"state-send:{conn.peer}")
                try:
                    while await conn.read(READ_CHUNK):
                        pass  # MotoROS ignores anything a state client sends
                except OSError as exc:  # a reset (clients often close with unread data), a timeout
                    if conn.logged:  # within the port's allowance (runtime/log_limit.py)
                        logger.info("state: client %s: connection lost (%s)", conn.peer, exc)
                finally:
                    sender.cancel()
        finally:
            self._clients.pop(conn, None)
            if client.dropped and conn.logged:
                logger.info(
                    "state: client %s received %d cycles; %d replaced by newer ones (slow reader)",
                    conn.peer,
                    client.sent,
                    client.dropped,
                )

    async def _send_loop(self, client: _StateClient) -> None:
        writer = client.conn.writer
        clock = self._clock
        gap = self.message_gap
        try:
            while True:
                await client.wakeup.wait()
                client.wakeup.clear()
                cycle = client.latest
                client.latest = None
                if cycle is None:
                    continue
                start = clock.now()
                for index, frame in enumerate(cycle):
                    if index:
                        await clock.sleep_until(start + index * gap)
                    client.conn.write(frame)  # recorded (sim --record)
                    await writer.drain()
                client.sent += 1
        except (ConnectionError, OSError) as exc:
            if client.conn.logged:
                logger.info("state: client %s: send failed (%s)", client.conn.peer, exc)
            client.conn.close()  # wakes the reader with EOF
