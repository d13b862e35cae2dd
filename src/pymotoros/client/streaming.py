"""Streaming a trajectory to MotoROS and seeing it through to the goal or to a stop.

:class:`TrajectoryStreamer` works against a narrow interface (a
:class:`~pymotoros.client.motion_port.MotionPort`, a
:class:`~pymotoros.client.motion_port.StateSource`, the models and an injected
:class:`~pymotoros.client.timing.ClientClock`):

* :meth:`~TrajectoryStreamer.send_points`: JOINT_TRAJ_PT_FULL(_EX)
  (:mod:`~pymotoros.client.point_messages`), sequence 0..N-1, each offered when MotoROS
  can take it (:mod:`~pymotoros.client.pacing`). BUSY (§3.4) is retried with a short,
  growing back-off under a per-point time budget; any other refusal raises the typed
  error with the point index and the numbers behind it
  (:mod:`~pymotoros.client.joint_text`).
* :meth:`~TrajectoryStreamer.wait_until_at_rest`: ``in_motion`` false and the feedback
  still (:mod:`~pymotoros.client.rest_detection`); its positions are the "start from
  current" point 0.
* :mod:`~pymotoros.client.following` compares feedback with the plan while the robot
  moves and reports how far behind it runs (how a safety speed limit shows up).
* :meth:`~TrajectoryStreamer.wait_for_completion`: queue empty, ``in_motion`` false,
  feedback settled within a tolerance of the goal; judged against progress, not only
  the clock. The result: :mod:`~pymotoros.client.move_result`.
* :meth:`~TrajectoryStreamer.stop_early`: whatever ends :meth:`~TrajectoryStreamer.execute`
  before the goal first stops the robot (STOP_MOTION, then at rest, within
  :data:`EARLY_STOP_BOUND_S`, safe from a second cancel: :mod:`~pymotoros.client.move_task`)
  and then lets the cancellation or error go on, saying where the robot stopped.

Every wait ends: on success, on a typed error, on a timeout, or at once with
:class:`ConnectionLostError` when a connection drops. The names that lived here before
the split (``BusyPolicy``, ``FollowingSample``, ``MoveResult``, ...) are still importable
from this module.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Sequence
from dataclasses import KW_ONLY, dataclass, field
from typing import Final

from pymotoros.client.errors import (
    AxisDeviation,
    ClientError,
    ConnectionLostError,
    EarlyStop,
    MotionConnectionLostError,
    MotionIncompleteError,
    MotionTimeoutError,
    ReplyError,
    StateStreamLostError,
    reply_error,
)
from pymotoros.client.following import (
    FollowingMonitor,
    FollowingReport,
    FollowingSample,
    PathProgress,
    joined_positions,
)
from pymotoros.client.joint_text import deviation_text, farthest_text, joint_values_text
from pymotoros.client.motion_port import MotionPort, StateSource
from pymotoros.client.move_result import MoveResult, StreamStats
from pymotoros.client.pacing import (
    BUSY_BACKOFF_FIRST_S,
    BUSY_BACKOFF_MAX_S,
    DEFAULT_BUSY_TIMEOUT_S,
    BusyPolicy,
    Pacing,
)
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.point_messages import build_message, message_type
from pymotoros.client.preflight import (
    speed_deviations,
    speed_screen,
    start_deviations,
    within_screen,
)
from pymotoros.client.rest_detection import RestDetector
from pymotoros.client.stopping import (
    STOP_ON_THE_PENDANT,
    STOP_REST_TIMEOUT_S,
    STOP_TIMEOUT_S,
    callback_guard,
    send_stop,
    shielded,
)
from pymotoros.client.timing import REAL_TIME, ClientClock
from pymotoros.client.watchdog import DEFAULT_STATE_STALL_S, StallWatchdog
from pymotoros.log_tags import AS_STOP_REPORT
from pymotoros.models import ControllerModel, GroupModel, RobotModel
from pymotoros.protocol.constants import InvalidSubcode, MotionCommand, ResultCode
from pymotoros.protocol.messages import (
    JointTrajPtFull,
    MotoJointTrajPtFullEx,
    MotoMotionReply,
)

__all__ = [  # the streamer's public names, wherever they are defined (users import them here)
    "DEFAULT_GOAL_TOLERANCE",
    "BusyPolicy",
    "EarlyStop",
    "FollowingReport",
    "FollowingSample",
    "MoveResult",
    "StreamStats",
    "TrajectoryStreamer",
    "deviation_text",
    "joint_values_text",
]

logger = logging.getLogger(__name__)

DEFAULT_GOAL_TOLERANCE: Final = 1e-4
"""rad (m): how close every joint must come to the goal (a few pulses on most arms)."""


DEFAULT_SETTLE_TIMEOUT_S: Final = 5.0
"""Extra time after the planned duration for the robot to settle."""


STALL_TIMEOUT_S: Final = 2.0
"""Past the planned duration, a robot that makes no progress for this long has stopped."""


@dataclass(frozen=True, slots=True)
class ExecuteOptions:
    """How one whole move is streamed and judged, as :meth:`RobotClient.execute` was
    asked: one bundle handed down from the public method, not its keywords copied."""

    busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S
    goal_tolerance: float = DEFAULT_GOAL_TOLERANCE
    timeout_s: float | None = None
    check_speed: bool = True
    on_progress: Callable[[FollowingSample], None] | None = None


@dataclass(eq=False, repr=False)
class TrajectoryStreamer:
    """Streams trajectories to one controller and watches the robot follow them.

    It depends only on a :class:`~pymotoros.client.motion_port.MotionPort` (request,
    queue count, readiness), a :class:`~pymotoros.client.motion_port.StateSource`
    (the state stream), the robot and controller models, and a
    :class:`~pymotoros.client.timing.ClientClock` for every "now" and "sleep": a test
    can drive it with an in-memory pair in virtual time. ``RobotClient`` builds one
    around itself.
    """

    port: MotionPort
    states: StateSource
    robot: RobotModel
    controller: ControllerModel
    _: KW_ONLY
    clock: ClientClock = REAL_TIME
    state_stall_s: float = DEFAULT_STATE_STALL_S
    """Seconds of state-stream silence after which :meth:`execute` stops the move
    (STOP_MOTION) and raises :class:`StateStreamLostError` (see ``client.watchdog``)."""
    busy_policy: BusyPolicy = BusyPolicy.PACED
    """When each point is first offered (BUSY handling, see :class:`BusyPolicy`)."""
    _stalled_for: float | None = field(default=None, init=False)
    _motion_gone: bool = field(default=False, init=False)
    _in_flight: int | None = field(default=None, init=False)
    """Sequence of the point sent and not yet answered, while there is one."""
    last_stop: EarlyStop | None = field(default=None, init=False)
    """How the latest :meth:`execute` that ended early stopped the robot (None: it did not)."""

    # ------------------------------------------------------------------ sending

    def _refusal(
        self,
        reply: MotoMotionReply,
        index: int,
        point: TrajectoryPoint,
        models: Sequence[GroupModel],
    ) -> ReplyError:
        devs: list[AxisDeviation] = []
        detail = ""
        if reply.result == ResultCode.INVALID and reply.subcode == InvalidSubcode.DATA_START_POS:
            groups = [self.robot.groups.index(m) for m in models]
            current = joined_positions(self.states.state, groups)
            devs = start_deviations(point, models, current, self.controller)
            detail = deviation_text(devs, "start", models) or "compared with the commanded position"
        elif reply.result == ResultCode.INVALID and reply.subcode == InvalidSubcode.DATA_SPEED:
            devs = speed_deviations(point, models, self.controller)
            detail = deviation_text(devs, "speed", models)
        return reply_error(
            reply.result, reply.subcode, reply.command, point=index, detail=detail, deviations=devs
        )

    async def send_point(
        self,
        message: JointTrajPtFull | MotoJointTrajPtFullEx,
        *,
        busy_timeout_s: float,
        stats: StreamStats,
        pacing: Pacing | None = None,
    ) -> MotoMotionReply:
        """Send one point, retrying BUSY; returns the final (non-BUSY) reply.

        With ``pacing`` (what is known to be queued ahead of the robot), the first offer
        waits until MotoROS can take it (:meth:`Pacing.first_wait`, unless
        :attr:`busy_policy` is IMMEDIATE), and a retry waits longer while plenty of
        motion is buffered; otherwise it backs off from 0.5 ms.
        """
        clock = self.clock
        backoff = BUSY_BACKOFF_FIRST_S
        first_busy: float | None = None
        if pacing is not None and self.busy_policy is BusyPolicy.PACED:
            wait = pacing.first_wait(clock.now())
            if wait > 0.0:
                await clock.sleep(wait)
        while True:
            lost = self.states.error
            if lost is not None:  # the state stream is gone: the move could not be watched
                raise ConnectionLostError(str(lost))
            if self._stalled_for is not None:  # never send a point blind
                raise _StreamStalledError
            self._in_flight = message.sequence
            if pacing is not None:
                pacing.sent_at = clock.now()
            reply = await self.port.request_motion(message)
            self._in_flight = None
            if reply.result != ResultCode.BUSY:
                if first_busy is not None:
                    stats.max_busy_wait_s = max(stats.max_busy_wait_s, clock.now() - first_busy)
                return reply
            stats.busy_replies += 1
            now = clock.now()
            if first_busy is None:
                first_busy = now
            elif now - first_busy > busy_timeout_s:
                stats.max_busy_wait_s = max(stats.max_busy_wait_s, now - first_busy)
                return reply
            relaxed = 0.0 if pacing is None else pacing.relaxed_wait(now)
            if relaxed > backoff:
                await clock.sleep(relaxed)
                continue
            await clock.sleep(backoff)
            backoff = min(backoff * 2, BUSY_BACKOFF_MAX_S)

    async def send_points(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        *,
        busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S,
        check_speed: bool = True,
        on_accepted: Callable[[int], None] | None = None,
    ) -> StreamStats:
        """Stream every point of ``trajectory`` (joints of ``groups`` concatenated, in order)."""
        models = [self.robot.groups[g] for g in groups]
        sizes = [m.num_axes for m in models]
        stats = StreamStats()
        started = self.clock.now()
        pacing: Pacing | None = None
        screen = speed_screen(models, self.controller) if check_speed else ()
        for index, point in enumerate(trajectory.points):
            # The screen passes only points the full check would pass without a word.
            if check_speed and not within_screen(point.velocities, screen):
                devs = speed_deviations(point, models, self.controller)
                if devs:
                    raise reply_error(
                        ResultCode.INVALID,
                        InvalidSubcode.DATA_SPEED,
                        message_type(groups),
                        point=index,
                        detail=deviation_text(devs, "speed", models) + "; checked before sending",
                        deviations=devs,
                    )
            message = build_message(point, index, groups, sizes)
            reply = await self.send_point(
                message, busy_timeout_s=busy_timeout_s, stats=stats, pacing=pacing
            )
            if reply.result == ResultCode.BUSY:
                raise reply_error(
                    reply.result,
                    reply.subcode,
                    reply.command,
                    point=index,
                    detail=f"BUSY for {busy_timeout_s:g} s after {stats.busy_replies} retries",
                )
            if reply.result != ResultCode.SUCCESS:
                raise self._refusal(reply, index, point, models)
            stats.points += 1
            if pacing is None:
                period = self.controller.interpolation_period_ms / 1000.0
                pacing = Pacing(self.clock.now(), point.time, period=period)
            else:
                pacing.accepted(point.time)
            if on_accepted is not None:
                on_accepted(index)
        stats.elapsed_s = self.clock.now() - started
        return stats

    # ------------------------------------------------------------------ watching

    async def wait_until_at_rest(
        self, groups: Sequence[int], *, timeout_s: float = 10.0
    ) -> tuple[float, ...]:
        """Wait until ``in_motion`` is false and the feedback is still; return its positions.

        This is "start from current": MotoROS checks point 0 against the commanded
        position with a 30-pulse tolerance, and right after a move, eco mode or a brake
        release the feedback still moves (users meet 3011 here).
        """
        states = self.states
        rest = RestDetector(groups)
        deadline = self.clock.now() + timeout_s
        try:
            # The loop's timeout bounds a silent stream; the clock's deadline bounds a
            # robot that keeps moving (both: a twin in virtual time keeps its meaning).
            async with asyncio.timeout(timeout_s):
                state = states.state
                while True:
                    pos = joined_positions(state, groups)
                    if rest.update(state) and pos is not None:
                        return pos
                    if self.clock.now() > deadline:
                        raise TimeoutError
                    state = await states.next_state()
        except TimeoutError:
            status = states.state.status
            raise MotionTimeoutError(
                f"the robot did not come to rest within {timeout_s:g} s "
                f"(in_motion={None if status is None else status.in_motion})"
            ) from None

    async def wait_for_completion(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        monitor: FollowingMonitor,
        *,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        settle_timeout_s: float = DEFAULT_SETTLE_TIMEOUT_S,
        timeout_s: float | None = None,
    ) -> tuple[float, ...]:
        """Wait until the queue is empty, ``in_motion`` false and the feedback settled at the goal.

        Past ``duration + settle_timeout_s`` the wait goes on while the robot still makes
        progress (a safety speed limit slows it, it has not stopped) and fails when it
        stalls for :data:`STALL_TIMEOUT_S` or passes ``timeout_s`` (default: 10 × duration
        + 30 s). A robot that stops because motion became impossible (E-stop, HOLD, alarm)
        raises :class:`NotReadyError` with the controller's reason.
        """
        states = self.states
        port = self.port
        clock = self.clock
        goal = trajectory.goal
        start = clock.now()
        soft_deadline = start + trajectory.duration + settle_timeout_s
        hard_deadline = start + (
            timeout_s if timeout_s is not None else 10 * trajectory.duration + 30
        )
        rest = RestDetector(groups)
        progress_of = PathProgress(trajectory)
        models = [self.robot.groups[g] for g in groups]
        best_progress, best_at = -1.0, start
        state = states.state
        while True:
            now = clock.now()
            positions = joined_positions(state, groups)
            status = state.status
            if positions is not None and status is not None:
                err = max(abs(p - g) for p, g in zip(positions, goal, strict=True))
                progress = progress_of(positions)
                if progress > best_progress + 1e-4:
                    best_progress, best_at = progress, now
                at_rest = rest.update(state)
                if at_rest and err <= goal_tolerance:
                    counts = [await port.queue_count(g) for g in groups]
                    if not any(counts):
                        return positions
                if not status.motion_possible:
                    readiness = await port.check_motion_ready()
                    if not readiness.ready and err > goal_tolerance:
                        raise reply_error(
                            ResultCode.FALSE,
                            readiness.subcode,
                            MotionCommand.CHECK_MOTION_READY,
                            detail=f"the robot stopped {farthest_text(positions, goal, models)} "
                            "from the goal",
                        )
                past_end = now > start + trajectory.duration + 1.0
                if at_rest and past_end and now - best_at > STALL_TIMEOUT_S:
                    raise MotionIncompleteError(
                        f"the robot came to rest {farthest_text(positions, goal, models)} "
                        f"from the goal, at {joint_values_text(positions, models)}, and is not "
                        "moving (was the motion stopped: STOP_MOTION from this client, HOLD or "
                        "the queue cleared?)"
                    )
            if now > hard_deadline or (now > soft_deadline and now - best_at > STALL_TIMEOUT_S):
                lag = monitor.report.max_lag_s
                raise MotionTimeoutError(
                    f"the move did not finish: planned {trajectory.duration:.2f} s, waited "
                    f"{now - start:.2f} s, progress {max(best_progress, 0.0):.0%}, largest lag "
                    f"{lag:.2f} s"
                )
            state = await states.next_state()

    # ------------------------------------------------------------------ a whole move

    async def execute(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        options: ExecuteOptions = ExecuteOptions(),
    ) -> MoveResult:
        """Stream ``trajectory``, follow the robot, and wait until it settled at the goal.

        Whatever ends the move early (a cancellation, a timeout around it, an exception of
        ``on_progress``, a refusal or error of the client's own) first stops the robot
        (:meth:`stop_early`: STOP_MOTION, then the feedback at rest, within
        :data:`EARLY_STOP_BOUND_S`), then goes on with the position where the robot stopped
        in its message (a note and a log for a ``CancelledError``, which stays one).
        """
        groups = tuple(groups)
        task = asyncio.current_task()
        failed: list[Exception] = []
        """An exception of the caller's progress callback: the move ends with it."""
        on_sample = options.on_progress
        if on_sample is not None:
            on_sample = callback_guard(on_sample, failed, task)
        monitor = FollowingMonitor(trajectory, groups, on_sample=on_sample, clock=self.clock)
        remove = self.states.add_listener(monitor.listen)
        started = self.clock.now()
        accepted_count = 0
        waiting = False
        cancel_later: list[asyncio.TimerHandle] = []
        self._stalled_for = None
        self._in_flight = None
        self.last_stop = None

        def accepted(index: int) -> None:
            nonlocal accepted_count
            accepted_count = index + 1
            if index == 1:
                monitor.start()

        def on_stall(silence: float) -> None:
            # While sending, the next point is simply not sent (a point in flight keeps its
            # reply, so the count of accepted points stays exact); while waiting, the wait
            # is cancelled.
            self._stalled_for = silence
            if task is None:
                return
            if waiting:
                task.cancel()
            else:  # a point whose reply never comes (the motion port went quiet too)
                grace = asyncio.get_running_loop().call_later(STOP_TIMEOUT_S, task.cancel)
                cancel_later.append(grace)

        watchdog = StallWatchdog(self.states, self.state_stall_s, on_stall, clock=self.clock)

        def disarm() -> None:
            # Before any stop: the callback and the monitor see no sample of it (a
            # callback raising then would turn the move's error into a cancellation,
            # and the monitor would blame FSU/HOLD for a robot the library stops).
            remove()  # idempotent: disarm runs again in ``finally``
            watchdog.close()
            for handle in cancel_later:
                handle.cancel()

        try:
            stats = await self.send_points(
                trajectory,
                groups,
                busy_timeout_s=options.busy_timeout_s,
                check_speed=options.check_speed,
                on_accepted=accepted,
            )
            accepted_count = stats.points
            monitor.start()
            waiting = True
            final = await self.wait_for_completion(
                trajectory,
                groups,
                monitor,
                goal_tolerance=options.goal_tolerance,
                timeout_s=options.timeout_s,
            )
        except _StreamStalledError:
            disarm()  # nothing may cancel the stop below
            raise await self._lost_shielded(
                groups, self._stalled_for, accepted_count, trajectory
            ) from None
        except asyncio.CancelledError as cancel:
            disarm()
            if task is not None and self._stalled():  # the watchdog's cancel, not a caller's
                task.uncancel()
                lost = await self._lost_shielded(
                    groups, self._stalled_for, accepted_count, trajectory
                )
                if task.cancelling():  # the caller cancelled too: that goes on
                    raise asyncio.CancelledError(str(lost)) from lost
                raise lost from None
            if failed and task is not None:  # the progress callback raised: end with it
                task.uncancel()
                error = failed[0]
                await self._stop_then(groups, error, "the progress callback raised")
                if task.cancelling():  # the caller cancelled too: that goes on
                    stop = self.last_stop
                    raise asyncio.CancelledError(stop.text if stop else "") from error
                raise error from None
            reason = f" ({cancel.args[0]})" if cancel.args and cancel.args[0] else ""
            await self._stop_then(groups, cancel, f"the move was cancelled{reason}")
            raise
        except ConnectionLostError as exc:
            if isinstance(exc, StateStreamLostError):
                raise
            if self.states.error is None:  # the motion port went: nothing can be stopped
                disarm()
                if accepted_count or self._in_flight is not None:
                    raise self._motion_lost(exc, groups, accepted_count, trajectory) from exc
                raise
            disarm()
            lost = await self._lost_shielded(groups, None, accepted_count, trajectory)
            if not lost.stopped and self._motion_gone:
                raise  # both went together (the controller closed): the plain loss says it
            raise lost from exc
        except BaseException as exc:  # a refusal, a timeout, KeyboardInterrupt in this thread
            disarm()
            if accepted_count:  # points are queued: the robot may move
                await self._stop_then(groups, exc, f"the move ended early ({type(exc).__name__})")
            raise
        finally:
            disarm()
        return MoveResult(
            trajectory, final, stats, monitor.report, self.clock.now() - started, groups
        )

    async def _stop_then(self, groups: Sequence[int], exc: BaseException, why: str) -> None:
        """:meth:`stop_early`, safe from further cancels, and ``exc`` told where it ended.

        The stop runs as a task of its own, awaited through :func:`asyncio.shield`: a
        second cancel (a ``wait_for`` around a ``wait_for``, a second Ctrl-C) does not cut
        it short; it is remembered, and a ``CancelledError`` goes on once the stop is
        done (at most :data:`EARLY_STOP_BOUND_S` later), so nothing is left half-done.
        """
        # The client's own errors carry the stop in their message: no second line in a log.
        level = logging.INFO if isinstance(exc, ClientError) else logging.WARNING
        outcome, cancelled_again = await shielded(self.stop_early(groups, why, quiet_level=level))
        self.last_stop = outcome
        outcome.tell(exc)
        if cancelled_again and not isinstance(exc, asyncio.CancelledError):
            raise asyncio.CancelledError(outcome.text) from exc

    async def _lost_shielded(
        self,
        groups: Sequence[int],
        silent_s: float | None,
        accepted: int,
        trajectory: JointTrajectory,
    ) -> StateStreamLostError:
        """:meth:`_stream_lost` safe from further cancels, as :meth:`_stop_then`: a cancel
        meanwhile goes on as a ``CancelledError`` (from the loss) once STOP_MOTION went."""
        lost, cancelled_again = await shielded(
            self._stream_lost(groups, silent_s, accepted, trajectory)
        )
        if cancelled_again:
            raise asyncio.CancelledError(str(lost)) from lost
        return lost

    async def stop_early(
        self, groups: Sequence[int], why: str, *, quiet_level: int = logging.WARNING
    ) -> EarlyStop:
        """Stop the robot after a move ended early: STOP_MOTION, then wait (at most
        :data:`STOP_REST_TIMEOUT_S`) until the feedback shows it at rest.

        Never raises for a stop that fails: the :class:`EarlyStop` says what happened,
        with the last known position and "stop the robot on the pendant" (logged as an
        error). A stop that worked is logged at ``quiet_level``: a warning where only a
        note carries it (a cancellation), INFO where the error's own message does.
        """
        started = self.clock.now()
        stopped, note = await self._send_stop(groups)
        at_rest = False
        rest_note = ""
        if stopped:
            try:
                await self.wait_until_at_rest(groups, timeout_s=STOP_REST_TIMEOUT_S)
                at_rest = True
            except ClientError as exc:  # a timeout, the state stream gone
                rest_note = f"; the feedback did not show it at rest ({exc})"
        models = [self.robot.groups[g] for g in groups]
        positions = joined_positions(self.states.state, groups) or ()
        where = joint_values_text(positions, models)
        took = self.clock.now() - started
        if at_rest:
            detail = f"the robot was stopped (STOP_MOTION) and stands at {where}"
            logger.log(
                quiet_level,
                "%s: %s (at rest %.3f s after the stop was sent)",
                why,
                detail,
                took,
                extra=AS_STOP_REPORT,
            )
        else:
            detail = f"{note}{rest_note}; last known position {where}"
            if stopped:
                detail += ": check that the robot stands, stop it on the pendant if not"
            logger.error("%s: %s", why, detail)
        return EarlyStop(stopped, at_rest, positions, took, why, detail)

    async def _send_stop(self, groups: Sequence[int]) -> tuple[bool, str]:
        """:func:`~pymotoros.client.stopping.send_stop`, remembering whether the motion
        connection was gone (a lost connection, not a refusal)."""
        stopped, self._motion_gone, note = await send_stop(self.port, groups[0])
        return stopped, note

    def forget_stop(self) -> None:
        """A new move starts: :attr:`last_stop` is no longer about it."""
        self.last_stop = None

    def _stalled(self) -> bool:
        """Has the watchdog tripped during the current :meth:`execute`? (set by its callback)"""
        return self._stalled_for is not None

    async def _stream_lost(
        self,
        groups: Sequence[int],
        silent_s: float | None,
        accepted: int,
        trajectory: JointTrajectory,
    ) -> StateStreamLostError:
        """Stop the robot (STOP_MOTION, if the motion port still answers) and say what was lost."""
        stopped, stop_note = await self._send_stop(groups)
        positions, where = self._last_known(groups)
        if silent_s is None:
            what = f"the state stream closed ({self.states.error})"
        else:
            what = (
                f"the state stream stalled: no state message for {silent_s:.2f} s "
                f"(bound {self.state_stall_s:g} s)"
            )
        total = len(trajectory.points)
        unanswered = (
            ""
            if self._in_flight is None
            else f" (point {self._in_flight} was sent and never answered: it may be queued too)"
        )
        message = (
            f"{what}; streaming stopped with {accepted} of {total} points accepted by the "
            f"robot{unanswered}; {stop_note}; last known position {where}. Check the network "
            "to the "
            "controller, then reconnect and move again from the current position"
        )
        logger.error("%s", message)
        return StateStreamLostError(
            message,
            silent_s=silent_s,
            positions=positions,
            accepted_points=accepted,
            total_points=total,
            stopped=stopped,
        )

    def _last_known(self, groups: Sequence[int]) -> tuple[tuple[float, ...], str]:
        """The last position the state stream reported and its text with units
        ("unknown" without one): what every error after a lost connection quotes."""
        positions = joined_positions(self.states.state, groups) or ()
        if not positions:
            return (), "unknown"
        return positions, joint_values_text(positions, [self.robot.groups[g] for g in groups])

    def _motion_lost(
        self,
        exc: ConnectionLostError,
        groups: Sequence[int],
        accepted: int,
        trajectory: JointTrajectory,
    ) -> MotionConnectionLostError:
        """The motion connection went mid-move while the state stream lives: MotoROS
        goes on with its queue (§2.2) and nothing can stop it from here."""
        positions, where = self._last_known(groups)
        total = len(trajectory.points)
        message = (
            f"{exc}; streaming stopped with {accepted} of {total} points accepted by the "
            "robot: the points already queued may still run (MotoROS goes on with its queue "
            "after the motion connection closes, reference §2.2) and STOP_MOTION cannot be "
            f"sent without it: {STOP_ON_THE_PENDANT}; last known position {where}"
        )
        logger.error("%s", message)
        return MotionConnectionLostError(
            message, positions=positions, accepted_points=accepted, total_points=total
        )


class _StreamStalledError(Exception):
    """Internal: the watchdog saw the state stream stall while points were being sent."""
