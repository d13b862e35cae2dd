"""StopMotion (§3.6): raise the stop flag, let the interpolators go idle, clear the queues."""

from __future__ import annotations

from typing import Final

from pymotoros.controller.processes import ControllerClock, Process
from pymotoros.controller.queues import MotionQueues
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.replies import SUCCESS, reply
from pymotoros.protocol.constants import ResultCode

STOP_WAIT_MS: Final = 20
"""StopMotion waits up to 20 × 1 ms for the interpolators to go idle (§3.6)."""


def stop_motion_now(readiness: Readiness, queues: MotionQueues) -> bool:
    """StopMotion from the IncMove task: no waiting (the task itself is the one stopping)."""
    readiness.flags.begin_stop()
    idle = not queues.any_pending()
    queues.clear()
    readiness.flags.end_stop()
    return idle


def stop_motion(readiness: Readiness, queues: MotionQueues, clock: ControllerClock) -> Process:
    """StopMotion (§3.6): stop flag, wait ≤ 20 ms for the interpolators, clear, unflag."""
    readiness.flags.begin_stop()
    start = clock.time_ms
    while queues.any_pending():
        if clock.time_ms - start >= STOP_WAIT_MS:
            break
        yield 1
    idle = not queues.any_pending()
    queues.clear()
    readiness.flags.end_stop()
    if idle:
        return SUCCESS
    return reply(
        ResultCode.FAILURE,
        detail=f"the interpolators did not go idle within {STOP_WAIT_MS} ms "
        "(the queues were cleared anyway)",
    )
