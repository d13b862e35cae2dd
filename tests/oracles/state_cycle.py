"""The twin's state cycle by its reference route: a broadcast task and message objects.

The twin runs the state cycle as clock callbacks that write to idle clients directly
(``StateServer.schedule_cycles``), each frame packed in one ``struct`` call and reused
while its values do not change (``StateServer.build_cycle``). The simulator runs the
same cycle as a task (``StateServer.broadcast``) with a sender task per client; and a
cycle's frames are, by definition, the validated message classes through ``encode``.
:func:`as_tasks` makes a twin (not started yet) do both, so the equality tests can
compare every byte a client receives, and when.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import JointFeedback, MotoJointFeedbackEx, RobotStatus
from pymotoros.runtime.state_server import StateServer
from pymotoros.testing import Twin


def build_cycle_reference(server: StateServer) -> tuple[bytes, ...]:
    """One cycle's frames through validated message objects and ``encode``."""
    c = server._controller
    order = server._order
    feedback = []
    for g in range(c.num_groups):
        data = c.joint_feedback(g)
        feedback.append(JointFeedback(data.group_no, data.valid_fields, 0.0, data.pos, data.vel))
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


def as_tasks(the_twin: Twin, *, reference_frames: bool = True) -> Twin:
    """``the_twin`` with its state cycle run as the simulator's broadcast task (and, with
    ``reference_frames``, built by :func:`build_cycle_reference`); returned for chaining.
    A failing cycle stops the twin with its error, as the callbacks do."""
    state = the_twin.state

    def schedule(_clock: object, on_error: Callable[[BaseException], None]) -> Callable[[], None]:
        task = asyncio.get_running_loop().create_task(
            state.broadcast(), name="twin-state-broadcast"
        )

        def failed(done: asyncio.Task[None]) -> None:
            if not done.cancelled() and done.exception() is not None:
                on_error(done.exception())  # type: ignore[arg-type]

        task.add_done_callback(failed)
        return task.cancel

    state.schedule_cycles = schedule  # type: ignore[assignment,method-assign]
    if reference_frames:
        state.build_cycle = lambda: build_cycle_reference(state)  # type: ignore[method-assign]
    return the_twin
