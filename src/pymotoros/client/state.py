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
        """Decode a ROBOT_STATUS message (MotoROS's ints: 1 true, 0 false, -1 unknown)."""
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
        """The fields as plain JSON values (``mode`` as its word, "play" or "teach"): the
        ``status`` object of ``pymotoros status --json``."""
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
        """The latest joint positions of ``group`` (rad, m for linear axes); None before its first
        feedback."""
        js = self.joints.get(group)
        return None if js is None else js.positions


Listener = Callable[[RobotState], None]

_VELOCITY: Final = int(ValidFields.VELOCITY)
"""A plain int: ``IntFlag`` operators are Python calls, and every feedback message asks."""

_same: Final = tuple.__eq__
"""Field-wise equality of two messages of the same class (their ``__eq__`` is Python)."""


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
        self._calling: tuple[Listener, ...] = ()
        """``tuple(self._listeners)``, kept in step by add/remove: what a message calls
        (a snapshot, so a listener may remove itself), without a copy per message."""
        self._waiting = 0
        """Coroutines inside :meth:`next_state`'s wait: with none, a message has nobody to
        wake, and the current unset event can stay (no set and no new Event per message)."""
        self._status_seen: tuple[RobotStatus, Status] | None = None
        """The last ROBOT_STATUS and its :class:`Status`: the status repeats every cycle
        while nothing changes, and an equal message gives an equal (immutable) Status."""
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
        pos = fb.pos
        used = len(pos)  # up to the last position that is not 0.0 (NaN counts as used)
        while used and pos[used - 1] == 0.0:
            used -= 1
        cycle = self._cycle
        group = fb.group_no
        seen = cycle.get(group, 0)
        cycle[group] = used if used > seen else seen

    @property
    def error(self) -> ConnectionLostError | None:
        return self._error

    def add_listener(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(state)`` on every state message; returns a function that removes it."""
        self._listeners.append(listener)
        self._calling = tuple(self._listeners)

        def remove() -> None:
            if listener in self._listeners:
                self._listeners.remove(listener)
                self._calling = tuple(self._listeners)

        return remove

    def _joint_state(self, fb: JointFeedback, now: float) -> JointState:
        group = fb.group_no
        axes = self._axes.get(group, 8)  # 8 slots at most (MotoROS zeros the last two)
        vel = fb.vel[:axes] if fb.valid_fields & _VELOCITY else None
        return JointState(group, fb.pos[:axes], vel, now)

    def _status(self, message: RobotStatus) -> Status:
        """``Status.from_message``, reused while ROBOT_STATUS repeats itself."""
        seen = self._status_seen
        if seen is not None and type(message) is type(seen[0]) and _same(message, seen[0]):
            return seen[1]
        status = Status.from_message(message)
        self._status_seen = (message, status)
        return status

    def feed(self, message: WireMessage) -> None:
        """Take one state-port message (the state connection's topic callback)."""
        old = self._state
        now = self._now()
        if isinstance(message, RobotStatus):
            status_count = old.status_count + 1
            if status_count >= STATUSES_FOR_A_FULL_CYCLE:
                self.groups_seen = MappingProxyType(dict(self._cycle))
            self._cycle = {}
            # The joints did not change: the same read-only view serves the new state.
            state = RobotState(self._status(message), old.joints, old.count + 1, status_count)
        elif isinstance(message, JointFeedback):
            joints = dict(old.joints)
            joints[message.group_no] = self._joint_state(message, now)
            self._saw(message)
            state = RobotState(
                old.status, MappingProxyType(joints), old.count + 1, old.status_count
            )
        elif isinstance(message, MotoJointFeedbackEx):
            joints = dict(old.joints)
            for fb in message.groups:
                joints[fb.group_no] = self._joint_state(fb, now)
                self._saw(fb)
            state = RobotState(
                old.status, MappingProxyType(joints), old.count + 1, old.status_count
            )
        else:
            logger.debug("state port: ignoring %r", message)
            return
        self._publish(state)

    def _publish(self, state: RobotState) -> None:
        self._state = state
        if self._waiting:
            self._changed.set()
            self._changed = asyncio.Event()
        for queue in self._queues:
            if queue.full():
                queue.get_nowait()
            queue.put_nowait(state)
        for listener in self._calling:
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
        self._waiting += 1
        try:
            async with asyncio.timeout(timeout_s):
                await event.wait()
        except TimeoutError:
            raise RequestTimeoutError(
                f"no state message for {timeout_s:g} s: is the state port streaming?"
            ) from None
        finally:
            self._waiting -= 1
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
