"""Joint-space motion: plan within the model's limits, stream, wait until settled, stop.

The motion part of :class:`~pymotoros.client.RobotClient`. A move starts where the
robot rests (from the state feedback), is planned jerk-limited within the robot
model's limits (:mod:`pymotoros.client.planning`) and streamed by the
:class:`~pymotoros.client.streaming.TrajectoryStreamer`; :meth:`Motion.stop` ends it
from another task (STOP_MOTION).
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

from pymotoros.client.alarms import alarm_text
from pymotoros.client.avoid import Avoidance
from pymotoros.client.connection import DEFAULT_REQUEST_TIMEOUT_S
from pymotoros.client.errors import (
    ClientError,
    MoveInProgressError,
    MoveStoppedError,
    NotReadyError,
)
from pymotoros.client.following import FollowingSample
from pymotoros.client.link import Link
from pymotoros.client.motion_commands import MotionCommands
from pymotoros.client.move_result import MoveResult
from pymotoros.client.pacing import DEFAULT_BUSY_TIMEOUT_S
from pymotoros.client.planning import (
    DEFAULT_SAMPLE_PERIOD_S,
    JointLimits,
    JointTrajectory,
    PlanningError,
    plan_joint_move,
)
from pymotoros.client.srdf import NamedPose, find_pose, parse_srdf
from pymotoros.client.state_view import StateView
from pymotoros.client.stopping import EARLY_STOP_BOUND_S
from pymotoros.client.streaming import DEFAULT_GOAL_TOLERANCE, ExecuteOptions, TrajectoryStreamer
from pymotoros.client.tools import ToolTable
from pymotoros.errors import PymotorosError
from pymotoros.models import ControllerModel, RobotModel
from pymotoros.protocol.constants import NotReadySubcode, Port

NAME_CONTACT_WAIT_S: Final = 2.0
"""Longest wait for a robot a contact stopped to come to rest before its error names
the contact (a collision alarm cuts servo power at once; a PFL stop backs off within
half a second)."""

JointGoal = Sequence[float] | Mapping[int, Sequence[float]] | Mapping[str, Sequence[float]]
"""A joint goal: positions for one group, or ``{group: positions}`` for several."""


@dataclass(eq=False, repr=False)
class Motion:
    """Joint moves of one client: planning, streaming, and stopping a running move."""

    _link: Link
    _view: StateView
    _commands: MotionCommands
    _streamer: TrajectoryStreamer
    _robot: RobotModel
    _controller: ControllerModel
    _avoidance: Avoidance | None = None
    """The cell's obstacles, for moves with ``avoid=True`` (None: the client has no cell)."""
    _moving: asyncio.Task[object] | None = field(default=None, init=False)
    """The task running this client's move, from its start (waiting for rest, planning)
    to its end: one move at a time (:meth:`one_move`)."""
    _move_name: str = field(default="", init=False)
    _stop_requested: bool = field(default=False, init=False)

    @contextlib.contextmanager
    def one_move(self, name: str) -> Iterator[None]:
        """Hold the client's one move for the current task while the block runs.

        MotoROS executes one trajectory at a time, and a second one streamed while the
        first runs is refused mid-way or, planned from the same start, ends far from its
        goal: a second move of this client is refused at once with
        :class:`MoveInProgressError`. The same task may nest (``move_pose`` calls
        ``move_joints``). A :meth:`stop` from elsewhere ends the block with
        :class:`MoveStoppedError` (once the robot has stopped).
        """
        task = asyncio.current_task()
        running = self._moving
        if running is not None and running is task:
            yield  # nested: the outer move holds it
            return
        if running is not None and not running.done():
            raise MoveInProgressError(
                f"{name}() refused: this client's {self._move_name}() is still running "
                "(MotoROS executes one trajectory at a time). Wait for it to end (await the "
                "task that runs it), or stop it first (await robot.stop(); from another "
                "thread robot.stop() of SyncRobotClient or stop_threadsafe()), then move again"
            )
        self._moving, self._move_name = task, name
        self._stop_requested = False
        self._streamer.forget_stop()
        terminated = _catch_sigterm(task)
        try:
            yield
        except asyncio.CancelledError:
            if not self._stop_requested or task is None:
                raise
            task.uncancel()
            stop = self._streamer.last_stop
            if stop is not None:  # its detail names STOP_MOTION already
                here, where = stop.positions, f"move stopped on request: {stop.detail}"
            else:  # stopped before anything was streamed
                groups = range(len(self._robot.groups))
                here = tuple(v for g in groups for v in (self._view.state.positions(g) or ()))
                where = "move stopped on request (STOP_MOTION): nothing was streamed yet"
            stopped = MoveStoppedError(where, positions=here)
            stopped.early_stop = stop
            raise stopped from None
        finally:
            self._moving = None
            if terminated():  # SIGTERM came: the robot is stopped, end as it would have
                signal.raise_signal(signal.SIGTERM)

    async def end_move(self, why: str = "the client is closing") -> None:
        """Cancel a move running in another task and wait (bounded) until it has stopped
        the robot: what :meth:`RobotClient.close` does first."""
        moving = self._moving
        if moving is None or moving.done() or moving is asyncio.current_task():
            return
        moving.cancel(why)
        await asyncio.wait([moving], timeout=EARLY_STOP_BOUND_S + 1.0)

    def limits(self, group: int | str = 0) -> JointLimits:
        """Planning limits of ``group`` from the robot model."""
        return JointLimits.from_group(
            self._robot.groups[self._view.group_index(group)],
            self._controller.interpolation_period_ms,
            self._controller.float_mode,
        )

    async def current_positions(
        self, group: int | Sequence[int] = 0, *, at_rest: bool = True, timeout_s: float = 10.0
    ) -> tuple[float, ...]:
        """Joint positions from feedback; with ``at_rest``, once the robot is settled."""
        groups = (group,) if isinstance(group, int) else tuple(group)
        await self._view.wait_for_state()
        if at_rest:
            return await self._streamer.wait_until_at_rest(groups, timeout_s=timeout_s)
        state = self._view.state
        return tuple(v for g in groups for v in (state.positions(g) or ()))

    def plan(
        self,
        start: Sequence[float],
        goal: Sequence[float],
        *,
        groups: Sequence[int] = (0,),
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        sample_period: float = DEFAULT_SAMPLE_PERIOD_S,
        avoid: bool = False,
        tool: int | None = None,
    ) -> JointTrajectory:
        """A synchronised point-to-point move (see :func:`planning.plan_joint_move`).

        ``avoid``: around the obstacles of the client's cell file (``RobotClient(cell=
        ...)``), searched as ``pymotoros plan --avoid`` searches (OMPL); the groups not in
        ``groups`` stand where the latest feedback has them. A goal that cannot be
        reached without a collision is a :class:`~pymotoros.errors.PathBlockedError`
        naming the obstacle (see :mod:`pymotoros.client.avoid`); with ``tool``'s shape on
        the flange of ``groups`` (default: the tool in force)."""
        limits = JointLimits.concat([self.limits(g) for g in groups])
        if avoid:
            return self._plan_avoiding(
                start, goal, groups, limits, speed_scale, accel_scale, sample_period, tool
            )
        return plan_joint_move(
            start,
            goal,
            limits,
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
            sample_period=sample_period,
        )

    def _plan_avoiding(
        self,
        start: Sequence[float],
        goal: Sequence[float],
        groups: Sequence[int],
        limits: JointLimits,
        speed_scale: float,
        accel_scale: float,
        sample_period: float,
        tool: int | None = None,
    ) -> JointTrajectory:
        """:meth:`plan` with ``avoid``: every group's start and goal, then the search."""
        avoidance = self._avoidance
        if avoidance is None:
            avoidance = self._avoidance = Avoidance(None, ToolTable(self._robot))
        if len(start) != limits.dof or len(goal) != limits.dof:
            raise PlanningError(
                f"expected {limits.dof} joint values ({', '.join(limits.names)}), "
                f"got start {len(start)} and goal {len(goal)}"
            )
        indices = [self._view.group_index(g) for g in groups]
        starts: list[tuple[float, ...]] = []
        goals: list[tuple[float, ...]] = []
        for index, group in enumerate(self._robot.groups):
            if index in indices:
                at = sum(self._robot.groups[g].num_axes for g in indices[: indices.index(index)])
                starts.append(tuple(start[at : at + group.num_axes]))
                goals.append(tuple(goal[at : at + group.num_axes]))
                continue
            here = self._view.state.positions(index)
            if here is None:
                raise PlanningError(
                    f"avoid needs where group {index} ({group.name}) stands, and no feedback "
                    "has told it yet: wait_for_state() first"
                )
            starts.append(here)
            goals.append(here)
        return avoidance.plan(
            starts,
            goals,
            indices,
            limits,
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
            sample_period=sample_period,
            tools=None if tool is None else dict.fromkeys(indices, tool),
        )

    async def execute(
        self,
        trajectory: JointTrajectory,
        *,
        groups: Sequence[int] = (0,),
        busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        timeout_s: float | None = None,
        check_speed: bool = True,
        on_progress: Callable[[FollowingSample], None] | None = None,
        force: bool = False,
        tool: int | None = None,
    ) -> MoveResult:
        """Stream ``trajectory`` and wait until the robot has settled at its last point.

        The trajectory's joints are those of ``groups`` one after the other; one group
        goes as JOINT_TRAJ_PT_FULL, several as JOINT_TRAJ_PT_FULL_EX. With a cell that
        has obstacles it is checked against them first (:meth:`guard`, with ``tool``'s
        shape; ``force`` skips).
        """
        # in the signature's order, which is ExecuteOptions' field order
        options = ExecuteOptions(
            busy_timeout_s, goal_tolerance, timeout_s, check_speed, on_progress
        )
        with self.one_move("execute"):  # a second move is refused before the guard
            return await self._guarded(trajectory, groups, options, force, tool)

    def guard(
        self, trajectory: JointTrajectory, groups: Sequence[int] = (0,), tool: int | None = None
    ) -> str | None:
        """Check ``trajectory`` (the joints of ``groups``) against the obstacles of the
        client's cell file at every interpolation tick, as every move of the client is
        before anything is sent (docs/workspace.md): a
        :class:`~pymotoros.errors.PathBlockedError` naming the time, link, obstacle and
        depth of the first contact; the note of a move that backs out of a contact the
        robot starts in; None when the way is clear or the client has no obstacles.
        ``tool``: the tool whose shape is on the flange of ``groups`` (the one the move
        was planned with), default the tool in force."""
        avoidance = self._avoidance
        if avoidance is None or not avoidance.guards:
            return None
        indices = [self._view.group_index(g) for g in groups]
        standing = [self._view.state.positions(g) for g in range(len(self._robot.groups))]
        period_s = self._controller.interpolation_period_ms / 1000.0
        tools = None if tool is None else dict.fromkeys(indices, tool)
        return avoidance.check(trajectory, indices, standing, period_s, tools)

    async def _guarded(
        self,
        trajectory: JointTrajectory,
        groups: Sequence[int],
        options: ExecuteOptions,
        force: bool,
        tool: int | None = None,
    ) -> MoveResult:
        """:meth:`_execute` after the workspace guard (unless ``force``); an error of a
        move a contact stopped names the contact where the robot stopped."""
        if not force:
            self.guard(trajectory, groups, tool)
        try:
            return await self._execute(trajectory, groups, options)
        except (MoveStoppedError, MoveInProgressError):
            raise
        except ClientError as exc:
            await self._name_contact(exc, groups)
            raise

    async def _name_contact(self, exc: ClientError, groups: Sequence[int]) -> None:
        """Add to ``exc`` the alarm and what the robot touches where it stopped, when the
        client's cell file has obstacles near it (the wire carries only the alarm
        number; the client computes the contact from its own cell file, once the robot
        has come to rest: at most :data:`NAME_CONTACT_WAIT_S`)."""
        avoidance = self._avoidance
        if avoidance is None or not avoidance.guards:
            return
        stop = exc.early_stop
        if stop is None or not stop.at_rest:  # else the library's stop saw it at rest
            with contextlib.suppress(PymotorosError, TimeoutError):
                await self._streamer.wait_until_at_rest(groups, timeout_s=NAME_CONTACT_WAIT_S)
        state = self._view.state
        standing = [state.positions(g) for g in range(len(self._robot.groups))]
        try:
            contact = avoidance.contact_at(standing)
        except PymotorosError:  # the message stays as it was
            return
        if contact is None:
            return
        status = state.status
        code = status.error_code if status is not None and status.in_error else 0
        if isinstance(exc, NotReadyError) and exc.reason is NotReadySubcode.PFL_ACTIVE:
            cause = f"PFL {NotReadySubcode.PFL_ACTIVE.value} (power and force limiting)"
        elif code:
            cause = f"alarm {code}" + (f" {alarm_text(code)}" if alarm_text(code) else "")
        else:
            cause = "the robot stopped"
        exc.args = (f"{exc}; {cause}: where it stopped, {contact}", *exc.args[1:])

    async def _execute(
        self, trajectory: JointTrajectory, groups: Sequence[int], options: ExecuteOptions
    ) -> MoveResult:
        """:meth:`execute` once its keywords are bundled (the moves here call it directly)."""
        with self.one_move("execute"):
            self._link.need(Port.STATE)  # completion is judged from the state stream
            groups = tuple(self._view.group_index(g) for g in groups)
            try:
                return await self._streamer.execute(trajectory, groups, options)
            except asyncio.CancelledError:
                await _others_stopped()  # SIGTERM: end only once every robot stands
                raise

    async def stop(self) -> None:
        """Stop the robot now (STOP_MOTION) and end a move running in another task.

        Safe from another task of the client's loop while :meth:`execute` /
        :meth:`move_joints` runs: that call raises :class:`MoveStoppedError`. From
        another thread use :meth:`stop_threadsafe`.
        """
        moving = self._moving
        if moving is not None and moving is not asyncio.current_task():
            self._stop_requested = True
            moving.cancel()
        await self._commands.stop_motion()

    def stop_threadsafe(self, timeout_s: float = DEFAULT_REQUEST_TIMEOUT_S) -> None:
        """:meth:`stop` from another thread (not the client's loop); waits for the reply."""
        loop = self._link.loop
        if loop is None or loop.is_closed():
            raise ClientError("the client is not connected: nothing to stop")
        if _in_loop(loop):
            raise ClientError("stop_threadsafe() called on the client's own loop: await stop()")
        asyncio.run_coroutine_threadsafe(self.stop(), loop).result(timeout_s)

    async def move_joints(
        self,
        goal: JointGoal,
        *,
        group: int | str = 0,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
        busy_timeout_s: float = DEFAULT_BUSY_TIMEOUT_S,
        timeout_s: float | None = None,
        avoid: bool = False,
        force: bool = False,
        tool: int | None = None,
    ) -> MoveResult:
        """Move to joint positions (rad/m, ROS order) from wherever the robot rests now.

        ``goal`` is a list for ``group``, or ``{group: positions}`` to move several
        groups together. Waits for the robot to be at rest, plans with the model's
        limits, streams, and waits until it has settled at the goal. ``avoid``: around
        the obstacles of the client's cell file (see :meth:`plan`); nothing is sent when
        the goal cannot be reached (:class:`~pymotoros.errors.PathBlockedError`). With
        obstacles in the cell file, a move that would touch one is refused before
        anything is sent (:meth:`guard`, with ``tool``'s shape on the flange, default the
        tool in force); ``force=True`` sends it anyway.
        """
        with self.one_move("move_joints"):
            if isinstance(goal, Mapping):
                groups = tuple(sorted(self._view.group_index(g) for g in goal))
                by_index = {self._view.group_index(g): v for g, v in goal.items()}
                target = tuple(v for g in groups for v in by_index[g])
            else:
                groups = (self._view.group_index(group),)
                target = tuple(goal)
            start = await self.current_positions(groups)
            trajectory = self.plan(
                start,
                target,
                groups=groups,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                avoid=avoid,
                tool=tool,
            )
            options = ExecuteOptions(
                busy_timeout_s, goal_tolerance, timeout_s, on_progress=on_progress
            )
            return await self._guarded(trajectory, groups, options, force, tool)

    def named_pose(
        self, name: str, *, srdf: str | Path | None = None, group: int | str = 0
    ) -> tuple[float, ...]:
        """Joint values of a named pose: an SRDF ``group_state`` or the built-in ``home``."""
        poses: tuple[NamedPose, ...] = parse_srdf(srdf) if srdf is not None else ()
        model = self._robot.groups[self._view.group_index(group)]
        return find_pose(name, model, poses).positions_for(model)

    async def move_named(
        self,
        name: str,
        *,
        srdf: str | Path | None = None,
        group: int = 0,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        force: bool = False,
    ) -> MoveResult:
        """Move to a named pose (``home``, or a ``group_state`` of ``srdf``); ``force``
        as for :meth:`move_joints`."""
        goal = self.named_pose(name, srdf=srdf, group=group)
        with self.one_move("move_named"):
            return await self.move_joints(
                goal,
                group=group,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                on_progress=on_progress,
                force=force,
            )


@dataclass
class _SigtermGuard:
    """The moves running on one event loop of the main thread, and the one SIGTERM
    handler that cancels them all (so that each stops its robot)."""

    loop: asyncio.AbstractEventLoop
    installed_as: object
    """What ``signal.getsignal(SIGTERM)`` gave right after the handler went in: when it
    differs at the end, the program installed its own since, and it is left alone."""
    tasks: set[asyncio.Task[object]] = field(default_factory=set)
    came: bool = False
    stopped: set[asyncio.Task[object]] = field(default_factory=set)
    """Moves that SIGTERM ended and that stopped their robot."""
    all_stopped: asyncio.Event = field(default_factory=asyncio.Event)

    def on_sigterm(self) -> None:
        self.came = True
        for task in tuple(self.tasks):
            task.cancel("SIGTERM")

    def check(self) -> None:
        """Every move SIGTERM ended has stopped: they may all go on (the first one's
        CancelledError must not end ``asyncio.run``, which would cancel the others'
        stops and close their connections)."""
        if self.came and self.stopped >= self.tasks:
            self.all_stopped.set()


async def _others_stopped() -> None:
    """After SIGTERM ended the current task's move (its robot stopped): wait until every
    other move of the loop has stopped its robot too; at once otherwise."""
    task = asyncio.current_task()
    guard = _SIGTERM_GUARDS.get(asyncio.get_running_loop())
    if guard is None or not guard.came or task is None:
        return
    guard.stopped.add(task)
    guard.check()
    waiting = asyncio.ensure_future(guard.all_stopped.wait())
    while not waiting.done():
        with contextlib.suppress(asyncio.CancelledError):
            await asyncio.shield(waiting)


_SIGTERM_GUARDS: dict[asyncio.AbstractEventLoop, _SigtermGuard] = {}
"""One guard per loop while a move runs on it (a process's signal disposition is
process-wide: one handler per loop, not one per move)."""


def _catch_sigterm(task: asyncio.Task[object] | None) -> Callable[[], bool]:
    """While moves run on an event loop of the main thread, SIGTERM with its default
    action (the process would end at once, the robots still moving) cancels every one of
    them instead, so that each stops its robot. The handler goes in with the first move
    (only while SIGTERM has its default action: a handler the program or the CLI
    installed is left alone) and out with the last (only if still ours). The returned
    function releases ``task``'s move and says whether SIGTERM came and this was the
    last move (the caller then raises it again, every robot stopped)."""
    if task is None or threading.current_thread() is not threading.main_thread():
        return _false
    loop = asyncio.get_running_loop()
    guard = _SIGTERM_GUARDS.get(loop)
    if guard is None:
        if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
            return _false
        guard = _SigtermGuard(loop, None)
        try:
            loop.add_signal_handler(signal.SIGTERM, guard.on_sigterm)
        except (NotImplementedError, RuntimeError, ValueError):  # no signals on this loop
            return _false
        guard.installed_as = signal.getsignal(signal.SIGTERM)
        _SIGTERM_GUARDS[loop] = guard
    guard.tasks.add(task)

    def release() -> bool:
        guard.tasks.discard(task)
        guard.check()
        if guard.tasks:
            return False  # another move still runs: it re-raises SIGTERM when it ends
        if _SIGTERM_GUARDS.get(loop) is guard:
            del _SIGTERM_GUARDS[loop]
        if signal.getsignal(signal.SIGTERM) is guard.installed_as:
            loop.remove_signal_handler(signal.SIGTERM)  # back to SIG_DFL
        return guard.came

    return release


def _false() -> bool:
    return False


def _in_loop(loop: asyncio.AbstractEventLoop) -> bool:
    try:
        return asyncio.get_running_loop() is loop
    except RuntimeError:
        return False
