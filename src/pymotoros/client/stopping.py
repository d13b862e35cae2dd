"""How a move that ends early stops the robot: STOP_MOTION (:func:`send_stop`) and the
time bounds of the stop, a stop that a second cancel cannot cut short (:func:`shielded`),
and the caller's progress callback whose error ends the move (:func:`callback_guard`).
:meth:`~pymotoros.client.streaming.TrajectoryStreamer.stop_early` puts them together."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine
from typing import Final, TypeVar

from pymotoros.client.errors import ClientError, ConnectionLostError, RequestTimeoutError
from pymotoros.client.following import FollowingSample
from pymotoros.client.motion_port import MotionPort
from pymotoros.protocol.constants import MotionCommand, ResultCode
from pymotoros.protocol.messages import MotoMotionCtrl

STOP_TIMEOUT_S: Final = 1.0
"""How long STOP_MOTION may take after the state stream was lost."""

STOP_REST_TIMEOUT_S: Final = 2.0
"""After STOP_MOTION, how long the feedback may take to show the robot at rest
(``in_motion`` false, still for :data:`SETTLE_SAMPLES` state cycles). MotoROS stops at
once (no ramp, §3.6): what is left is the servo's own lag and three quiet state cycles
(~75 ms), so 2 s is ample and still short enough for a person waiting on Ctrl-C."""

EARLY_STOP_BOUND_S: Final = STOP_TIMEOUT_S + STOP_REST_TIMEOUT_S
"""The longest a move that ends early holds up its cancellation or error to stop the
robot: the STOP_MOTION reply plus the wait for rest (3 s; docs/client.md)."""

STOP_ON_THE_PENDANT: Final = "stop the robot on the pendant"
"""What to do when STOP_MOTION could not be sent or was not answered (one wording, here)."""

_T = TypeVar("_T")


async def shielded(work: Coroutine[object, object, _T]) -> tuple[_T, bool]:
    """Run ``work`` as a task of its own, awaited through :func:`asyncio.shield` until it
    is done: (its result, whether the caller was cancelled meanwhile). A stop that a
    second cancel (a ``wait_for`` around a ``wait_for``, a second Ctrl-C) cut short
    would leave the robot moving; the caller re-raises the cancel once it is done."""
    running = asyncio.ensure_future(work)
    cancelled_again = False
    while True:
        try:
            return await asyncio.shield(running), cancelled_again
        except asyncio.CancelledError:
            cancelled_again = True
            if running.done():  # cancelled as it finished: keep what it did
                if running.cancelled():  # the loop itself is going away
                    raise
                return running.result(), cancelled_again


def callback_guard(
    callback: Callable[[FollowingSample], None],
    failed: list[Exception],
    task: asyncio.Task[object] | None,
) -> Callable[[FollowingSample], None]:
    """``callback`` for the following monitor: its first exception is kept in ``failed``
    and cancels the move's task (the move then stops the robot and raises it); later
    samples are not passed on."""

    def guarded(sample: FollowingSample) -> None:
        if failed:
            return
        try:
            callback(sample)
        except Exception as exc:
            failed.append(exc)
            if task is not None:
                task.cancel()

    return guarded


async def send_stop(port: MotionPort, group: int) -> tuple[bool, bool, str]:
    """STOP_MOTION within :data:`STOP_TIMEOUT_S`: (acknowledged, the motion connection is
    gone, what happened). The one place that words a failed stop ("stop the robot on the
    pendant")."""
    try:
        reply = await port.request_motion(
            MotoMotionCtrl(group, 0, int(MotionCommand.STOP_MOTION)),
            timeout_s=STOP_TIMEOUT_S,
        )
    except (ConnectionLostError, RequestTimeoutError) as exc:
        gone = isinstance(exc, ConnectionLostError)
        return False, gone, f"STOP_MOTION could not be sent ({exc}): {STOP_ON_THE_PENDANT}"
    except ClientError as exc:
        return False, False, f"STOP_MOTION failed ({exc}): {STOP_ON_THE_PENDANT}"
    if reply.result == ResultCode.SUCCESS:
        return True, False, "STOP_MOTION acknowledged"
    return (
        False,
        False,
        (
            f"STOP_MOTION refused (result {reply.result}, subcode {reply.subcode}): "
            f"{STOP_ON_THE_PENDANT}"
        ),
    )
