"""The robot's latest state as the state port streams it, and ways to wait on it.

MotoROS sends, about 40 times a second, JOINT_FEEDBACK for each group,
JOINT_FEEDBACK_EX when there are two groups or more, then ROBOT_STATUS (§2.3).
:class:`StateTracker` keeps the latest of each as frozen snapshots, calls
listeners (outside any lock), feeds async iterators ("latest wins", never an
unbounded queue) and lets coroutines wait for a condition with a timeout; losing
the state connection wakes every waiter with :class:`ConnectionLostError`.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncIterator, Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Final

from pymotoros.client.errors import ConnectionLostError, RequestTimeoutError
from pymotoros.protocol.constants import PendantMode, StatusMode, ValidFields
from pymotoros.protocol.messages import (
    JointFeedback,
    MotoJointFeedbackEx,
    RobotStatus,
    WireMessage,
)

logger = logging.getLogger(__name__)

STATUSES_FOR_A_FULL_CYCLE: Final = 2
"""Each state cycle ends with ROBOT_STATUS (§2.3); the client may join the first cycle
half-way, so the groups are known from the second ROBOT_STATUS on."""

DEFAULT_STATE_TIMEOUT_S: Final = 2.0
"""No state message for this long means the state stream is dead (MotoROS sends ~40 Hz)."""


Mode = PendantMode
"""ROBOT_STATUS ``mode`` as the client reports it (decoded by ``StatusMode.is_play``, §2.6):
the same enum the twin's pendant uses."""


@dataclass(frozen=True, slots=True)
class Status:
    """ROBOT_STATUS as booleans. ``in_motion`` is None for MotoROS's rare "unknown" (-1)."""

    drives_powered: bool
    e_stopped: bool
    error_code: int
    in_error: bool
    in_motion: bool | None
    mode: Mode
    motion_possible: bool

    @classmethod
    def from_message(cls, msg: RobotStatus) -> Status:
        return cls(
            drives_powered=msg.drives_powered == 1,
            e_stopped=msg.e_stopped == 1,
            error_code=msg.error_code,
            in_error=msg.in_error == 1,
            in_motion=None if msg.in_motion < 0 else msg.in_motion == 1,
            mode=Mode.PLAY if StatusMode.is_play(msg.mode) else Mode.TEACH,
            motion_possible=msg.motion_possible == 1,
        )

    def as_dict(self) -> dict[str, object]:
        return {
            "drives_powered": self.drives_powered,
            "e_stopped": self.e_stopped,
            "error_code": self.error_code,
            "in_error": self.in_error,
            "in_motion": self.in_motion,
            "mode": self.mode.value,
            "motion_possible": self.motion_possible,
        }


@dataclass(frozen=True, slots=True)
class JointState:
    """One group's feedback: positions (rad/m) and velocities, in ROS joint order."""

    group: int
    positions: tuple[float, ...]
    velocities: tuple[float, ...] | None
    received: float
    """When it arrived, on the client's clock (``time.monotonic()`` unless one was injected)."""


@dataclass(frozen=True, slots=True)
class RobotState:
    """Everything the state port has said, as of one message."""

    status: Status | None = None
    joints: Mapping[int, JointState] = field(default_factory=lambda: MappingProxyType({}))
    count: int = 0
    """Number of state messages received so far."""
    status_count: int = 0
    """Number of ROBOT_STATUS messages received so far (one per state cycle)."""

    def positions(self, group: int = 0) -> tuple[float, ...] | None:
        js = self.joints.get(group)
        return None if js is None else js.positions


Listener = Callable[[RobotState], None]


class StateTracker:
    """Latest state, listeners, iterators and waits; fed by the state connection."""

    def __init__(
        self,
        axes_per_group: Mapping[int, int] | None = None,
        *,
        now: Callable[[], float] = time.monotonic,
    ) -> None:
        self._axes = dict(axes_per_group or {})
        self._now = now
        self._state = RobotState()
        self._listeners: list[Listener] = []
        self._queues: set[asyncio.Queue[RobotState]] = set()
        self._changed = asyncio.Event()
        self._error: ConnectionLostError | None = None
        self._cycle: dict[int, int] = {}
        self.groups_seen: Mapping[int, int] | None = None
        """The groups whose feedback came in the last full state cycle (between two
        ROBOT_STATUS), each with the number of joint slots up to its last non-zero
        position (MotoROS sends zeros in unused slots): None until a full cycle was seen."""

    @property
    def state(self) -> RobotState:
        return self._state

    def _saw(self, fb: JointFeedback) -> None:
        used = max((i + 1 for i, v in enumerate(fb.pos) if v != 0.0), default=0)
        self._cycle[fb.group_no] = max(used, self._cycle.get(fb.group_no, 0))

    @property
    def error(self) -> ConnectionLostError | None:
        return self._error

    def add_listener(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(state)`` on every state message; returns a function that removes it."""
        self._listeners.append(listener)

        def remove() -> None:
            if listener in self._listeners:
                self._listeners.remove(listener)

        return remove

    def _trim(self, group: int, values: tuple[float, ...]) -> tuple[float, ...]:
        return values[: self._axes.get(group, 8)]

    def _joint_state(self, fb: JointFeedback, now: float) -> JointState:
        vel = self._trim(fb.group_no, fb.vel) if fb.valid_fields & ValidFields.VELOCITY else None
        return JointState(fb.group_no, self._trim(fb.group_no, fb.pos), vel, now)

    def feed(self, message: WireMessage) -> None:
        """Take one state-port message (the state connection's topic callback)."""
        old = self._state
        now = self._now()
        status, status_count = old.status, old.status_count
        joints = dict(old.joints)
        if isinstance(message, RobotStatus):
            status = Status.from_message(message)
            status_count += 1
            if status_count >= STATUSES_FOR_A_FULL_CYCLE:
                self.groups_seen = MappingProxyType(dict(self._cycle))
            self._cycle = {}
        elif isinstance(message, JointFeedback):
            joints[message.group_no] = self._joint_state(message, now)
            self._saw(message)
        elif isinstance(message, MotoJointFeedbackEx):
            for fb in message.groups:
                joints[fb.group_no] = self._joint_state(fb, now)
                self._saw(fb)
        else:
            logger.debug("state port: ignoring %r", message)
            return
        self._publish(RobotState(status, MappingProxyType(joints), old.count + 1, status_count))

    def _publish(self, state: RobotState) -> None:
        self._state = state
        self._changed.set()
        self._changed = asyncio.Event()
        for queue in self._queues:
            if queue.full():
                queue.get_nowait()
            queue.put_nowait(state)
        for listener in list(self._listeners):
            try:
                listener(state)
            except Exception:
                logger.exception("state listener %r failed", listener)

    def lost(self, error: ConnectionLostError) -> None:
        """The state connection is gone: wake every waiter with ``error``."""
        if self._error is None:
            self._error = error
        self._changed.set()
        for queue in self._queues:
            if queue.full():
                queue.get_nowait()
            queue.put_nowait(self._state)

    def _check(self) -> None:
        if self._error is not None:
            raise ConnectionLostError(str(self._error))

    async def next_state(self, timeout_s: float = DEFAULT_STATE_TIMEOUT_S) -> RobotState:
        """Wait for the next state message."""
        self._check()
        event = self._changed
        try:
            async with asyncio.timeout(timeout_s):
                await event.wait()
        except TimeoutError:
            raise RequestTimeoutError(
                f"no state message for {timeout_s:g} s: is the state port streaming?"
            ) from None
        self._check()
        return self._state

    async def wait_for(
        self,
        predicate: Callable[[RobotState], bool],
        timeout_s: float,
        *,
        what: str = "the condition",
        message_timeout_s: float = DEFAULT_STATE_TIMEOUT_S,
    ) -> RobotState:
        """Wait until ``predicate(state)`` holds; checks the current state first."""
        self._check()
        try:
            async with asyncio.timeout(timeout_s):
                state = self._state
                while not predicate(state):
                    state = await self.next_state(message_timeout_s)
                return state
        except TimeoutError:
            raise RequestTimeoutError(
                f"timed out after {timeout_s:g} s waiting for {what}"
            ) from None

    async def states(
        self, message_timeout_s: float = DEFAULT_STATE_TIMEOUT_S
    ) -> AsyncIterator[RobotState]:
        """Every state message (latest wins if the consumer is slow).

        Raises :class:`ConnectionLostError` when the stream ends and
        :class:`RequestTimeoutError` when it falls silent for ``message_timeout_s``.
        """
        queue: asyncio.Queue[RobotState] = asyncio.Queue(maxsize=1)
        self._queues.add(queue)
        try:
            while True:
                self._check()
                try:
                    async with asyncio.timeout(message_timeout_s):
                        state = await queue.get()
                except TimeoutError:
                    raise RequestTimeoutError(
                        f"no state message for {message_timeout_s:g} s: "
                        "is the state port streaming?"
                    ) from None
                self._check()
                yield state
        finally:
            self._queues.discard(queue)
