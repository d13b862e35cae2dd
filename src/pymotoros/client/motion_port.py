"""The narrow interfaces trajectory streaming depends on, instead of the whole client.

:class:`~pymotoros.client.streaming.TrajectoryStreamer` needs three requests of the
motion port (send a request, read a queue count, ask CHECK_MOTION_READY) and the
state stream (the latest state, the next one, whether it is lost). ``RobotClient``
and ``StateTracker`` provide them; a test can provide them in memory. Keeping these
here means ``streaming`` never imports ``robot`` (no import cycle).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from pymotoros.client.errors import ConnectionLostError
from pymotoros.client.state import RobotState
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.protocol.messages import MotoMotionReply, WireMessage

__all__ = ["MotionPort", "MotionReadiness", "StateSource"]


@dataclass(frozen=True, slots=True)
class MotionReadiness:
    """Answer to CHECK_MOTION_READY: ready, or the reason it is not, with what to do.

    (Named apart from the controller's own ``Readiness``, the domain's answer.)
    """

    ready: bool
    subcode: int
    reason: NotReadySubcode | None
    meaning: str
    remedy: str


class MotionPort(Protocol):
    """The motion-port requests streaming uses."""

    async def request_motion(
        self, message: WireMessage, *, timeout_s: float | None = None
    ) -> MotoMotionReply:
        """Send a request answered by a MOTO_MOTION_REPLY; return the reply as is."""
        ...

    async def queue_count(self, group: int = 0) -> int:
        """Increments still queued for ``group`` (CHECK_QUEUE_CNT)."""
        ...

    async def check_motion_ready(self) -> MotionReadiness:
        """CHECK_MOTION_READY, never raising for "not ready"."""
        ...


class StateSource(Protocol):
    """The state stream as streaming watches it (``StateTracker`` is one)."""

    @property
    def state(self) -> RobotState:
        """The latest state."""
        ...

    @property
    def error(self) -> ConnectionLostError | None:
        """Why the state stream is gone, or None while it is up."""
        ...

    async def next_state(self) -> RobotState:
        """Wait for the next state message."""
        ...

    def add_listener(self, listener: Callable[[RobotState], None]) -> Callable[[], None]:
        """Call ``listener(state)`` on every state message; returns the function removing it."""
        ...
