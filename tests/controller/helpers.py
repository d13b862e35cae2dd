"""Helpers for driving a VirtualController in a plain loop (virtual time, no event loop)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial

from pymotoros.controller import Outcome, Pending, PointData, VirtualController
from pymotoros.protocol.constants import MotionCommand, ResultCode

MAX_TICKS = 3000
"""Default bound of every 'tick until' loop: 12 s of controller time at 4 ms."""

CMD = MotionCommand


def pad(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in values) + (0.0,) * (10 - len(values))


def point(
    group: int,
    time: float,
    pos: Sequence[float],
    vel: Sequence[float] | None = None,
    fields: int = 7,
) -> PointData:
    """A JOINT_TRAJ_PT_FULL body for one group (ROS order, rad, rad/s)."""
    return PointData(group, fields, time, pad(pos), pad(vel or [0.0] * len(pos)), pad([]))


def tick_until(
    vc: VirtualController, condition: Callable[[], bool], what: str, max_ticks: int = MAX_TICKS
) -> int:
    """Tick until ``condition()``; fail clearly after ``max_ticks``. Returns the ticks used."""
    for n in range(max_ticks + 1):
        if condition():
            return n
        vc.tick()
    raise AssertionError(f"{what}: not reached within {max_ticks} ticks ({vc.time_ms} ms)")


def complete(
    vc: VirtualController, result: Outcome | Pending, max_ticks: int = MAX_TICKS
) -> Outcome:
    """The Outcome of a request, ticking while it is pending (bounded)."""
    if isinstance(result, Outcome):
        return result
    tick_until(vc, lambda: result.done, result.description, max_ticks)
    return result.outcome


def command(vc: VirtualController, cmd: int, group: int = 0) -> Outcome:
    return complete(vc, vc.motion_ctrl(group, cmd))


def enter_traj_mode(vc: VirtualController) -> None:
    outcome = command(vc, CMD.START_TRAJ_MODE)
    assert outcome.ok, outcome


def current_pos(vc: VirtualController, group: int = 0) -> list[float]:
    return list(vc.snapshot().groups[group].command_rad)


def resend_while_busy(
    vc: VirtualController, request: Callable[[], Outcome | Pending], max_busy: int = 1000
) -> tuple[Outcome, int]:
    """``request()``'s answer, resent after a tick while it is BUSY (as clients do, §2),
    at most ``max_busy`` times; the last answer (still BUSY if that was not enough) and
    the number of BUSY answers."""
    for busy in range(max_busy):
        outcome = complete(vc, request())
        if outcome.result != ResultCode.BUSY:
            return outcome, busy
        vc.tick()
    return outcome, max_busy


def send(vc: VirtualController, sequence: int, p: PointData, max_busy: int = 1000) -> Outcome:
    """Send a point, resending after a tick while BUSY (as clients do)."""
    outcome, _ = resend_while_busy(vc, partial(vc.trajectory_point, sequence, p), max_busy)
    if outcome.result == ResultCode.BUSY:
        raise AssertionError(f"point {sequence} still BUSY after {max_busy} ticks")
    return outcome


def start_at_current(vc: VirtualController, group: int = 0) -> Outcome:
    pos = current_pos(vc, group)
    return send(vc, 0, point(group, 0.0, pos))
