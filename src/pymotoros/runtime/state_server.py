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
from collections.abc import Callable
from typing import Final, Protocol, Unpack

from pymotoros.controller.api import FeedbackData, MotoRosController
from pymotoros.protocol.constants import ByteOrder
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import JointFeedback, MotoJointFeedbackEx
from pymotoros.protocol.state_frames import joint_feedback_frame, robot_status_frame
from pymotoros.runtime.clock import Clock
from pymotoros.runtime.connections import STATE_CLIENTS
from pymotoros.runtime.tcp import READ_CHUNK, Connection, ServiceWiring, TcpService

__all__ = ["STATE_MESSAGE_GAP_S", "STATE_PERIOD_S", "StateServer"]

logger = logging.getLogger(__name__)


class CallbackHandle(Protocol):
    def cancel(self) -> None: ...


class CallbackClock(Protocol):
    """A clock that runs callbacks at deadlines (:class:`~pymotoros.runtime.clock.ManualClock`)."""

    def now(self) -> float: ...

    def call_at(self, deadline: float, callback: Callable[[], object]) -> CallbackHandle: ...


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

    __slots__ = ("conn", "dropped", "latest", "sending", "sent", "wakeup")

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.latest: tuple[bytes, ...] | None = None
        self.sending = False
        """The sender task is writing a cycle (between two messages of its gap)."""
        self.wakeup = asyncio.Event()
        self.dropped = 0
        self.sent = 0

    def idle(self) -> bool:
        """Nothing pending or being sent, and the transport's buffer is empty: a cycle
        written now goes out exactly as the sender task would write it."""
        return (
            self.latest is None
            and not self.sending
            and not self.conn.writer.transport.get_write_buffer_size()
        )

    def send_now(self, cycle: tuple[bytes, ...]) -> None:
        """Write the whole cycle at once (messages without a gap between them)."""
        for frame in cycle:
            self.conn.write(frame)  # recorded (sim --record)
        self.sent += 1

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
        **wiring: Unpack[ServiceWiring],
    ) -> None:
        """``wiring``: what the application gives (``runtime.tcp.ServiceWiring``)."""
        super().__init__(STATE_CLIENTS, lambda: controller.has_queued_motion(), **wiring)
        self._controller = controller
        self._order = order
        self._clock = clock
        self.period = period
        self.message_gap = message_gap
        self._clients: dict[Connection, _StateClient] = {}
        self.cycles = 0
        self._frames: dict[int, tuple[object, bytes]] = {}
        """The last frame per group (key −1: the status), with the values it encodes."""

    # ----------------------------------------------------------- cycles

    def build_cycle(self) -> tuple[bytes, ...]:
        """The frames of one state cycle, encoded: feedback per group, EX if ≥ 2, status.

        One pack per frame (:mod:`pymotoros.protocol.state_frames`); a frame whose values
        did not change since the last cycle (a group at rest, an unchanged status) is
        the same bytes object again. The tests compare the bytes with those the message
        classes and ``encode`` make (``tests/oracles/state_cycle.py``)."""
        c = self._controller
        order = self._order
        memo = self._frames
        frames: list[bytes] = []
        feedback: list[FeedbackData] = []
        for g in range(c.num_groups):
            data = c.joint_feedback(g)
            feedback.append(data)
            if memo.get(g, (None,))[0] is not data:  # the view returns the same object at rest
                memo[g] = (
                    data,
                    joint_feedback_frame(
                        order, data.group_no, data.valid_fields, data.pos, data.vel
                    ),
                )
            frames.append(memo[g][1])
        if len(feedback) >= 2:
            frames.append(
                encode(
                    MotoJointFeedbackEx.for_groups(
                        [
                            JointFeedback(d.group_no, d.valid_fields, 0.0, d.pos, d.vel)
                            for d in feedback
                        ]
                    ),
                    order,
                )
            )
        s = c.robot_status()
        status = (
            s.drives_powered,
            s.e_stopped,
            s.error_code,
            s.in_error,
            s.in_motion,
            s.mode,
            s.motion_possible,
        )
        last = memo.get(-1)
        if last is None or last[0] != status:
            memo[-1] = last = (status, robot_status_frame(order, status))
        frames.append(last[1])
        return tuple(frames)

    def broadcast_cycle(self, *, direct: bool = False) -> None:
        """One cycle: build it and offer it to every client (nothing without clients).

        With ``direct`` and no gap between messages, a client whose sender is idle gets
        the cycle written at once instead of through its sender task: the same bytes at
        the same (virtual) time, one task wake-up fewer per client and cycle."""
        if not self._clients:
            return
        cycle = self.build_cycle()
        self.cycles += 1
        direct = direct and not self.message_gap
        for client in self._clients.values():
            if direct and client.idle():
                client.send_now(cycle)
            else:
                client.offer(cycle)

    async def broadcast(self) -> None:
        """Offer a fresh cycle to every client every period, until cancelled."""
        clock = self._clock
        deadline = clock.now()
        while True:
            self.broadcast_cycle()
            deadline += self.period
            now = clock.now()
            if now - deadline > self.period:
                deadline = now  # stalled: restart the rhythm instead of bursting
            await clock.sleep_until(deadline)

    def schedule_cycles(
        self, clock: CallbackClock, on_error: Callable[[BaseException], None]
    ) -> Callable[[], None]:
        """:meth:`broadcast` as clock callbacks, for a virtual clock (the in-memory twin).

        The same cycles at the same times and in the same order among the clock's
        sleepers as the :meth:`broadcast` task (its deadlines by the same arithmetic),
        written directly to idle clients: no task wakes per cycle. An exception goes to
        ``on_error`` (the twin stops with it, as when the task fails). Returns the
        function that stops the cycles."""
        deadline = clock.now()
        handle: CallbackHandle | None = None

        def cycle() -> None:
            nonlocal deadline, handle
            try:
                self.broadcast_cycle(direct=True)
            except Exception as exc:
                on_error(exc)
                return
            deadline += self.period
            now = clock.now()
            if now - deadline > self.period:
                deadline = now
            handle = clock.call_at(deadline, cycle)

        handle = clock.call_at(deadline, cycle)

        def stop() -> None:
            if handle is not None:
                handle.cancel()

        return stop

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
                client.sending = True
                try:
                    for index, frame in enumerate(cycle):
                        if index:
                            await clock.sleep_until(start + index * gap)
                        client.conn.write(frame)  # recorded (sim --record)
                        await writer.drain()
                finally:
                    client.sending = False
                client.sent += 1
        except (ConnectionError, OSError) as exc:
            if client.conn.logged:
                logger.info("state: client %s: send failed (%s)", client.conn.peer, exc)
            client.conn.close()  # wakes the reader with EOF
