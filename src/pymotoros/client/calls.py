"""Every call of the robot client, defined once: :class:`RobotCalls`.

:class:`~pymotoros.client.RobotClient` (async) and
:class:`~pymotoros.client.SyncRobotClient` (blocking) both inherit these methods; the
decorators of :mod:`pymotoros.client.blocking` make a coroutine method awaited on the
first and blocking on the second. Each method does its work through one of the client's
parts (:class:`ClientParts`), each testable on its own: the motion port's requests
(:class:`~pymotoros.client.motion_commands.MotionCommands`), the state stream and the
model checks (:class:`~pymotoros.client.state_view.StateView`), the IO image
(:class:`~pymotoros.client.io_port.IoPort`), joint motion
(:class:`~pymotoros.client.motion.Motion`) and the TCP
(:class:`~pymotoros.client.geometry.Geometry`).

A new wire request: its method in the part, and one method here (both clients get it).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from pymotoros.client.blocking import after_first_state, blocking_twin, facade_plain
from pymotoros.client.connection import DEFAULT_REQUEST_TIMEOUT_S
from pymotoros.client.following import FollowingSample
from pymotoros.client.geometry import CartesianFrame, Geometry, Pose
from pymotoros.client.io_port import IoPort
from pymotoros.client.motion import JointGoal, Motion
from pymotoros.client.motion_commands import MotionCommands
from pymotoros.client.motion_port import MotionReadiness
from pymotoros.client.move_result import MoveResult
from pymotoros.client.pacing import DEFAULT_BUSY_TIMEOUT_S
from pymotoros.client.planning import DEFAULT_SAMPLE_PERIOD_S, JointLimits, JointTrajectory
from pymotoros.client.registers import RegisterValues, read_register_outputs, s1cxg_table
from pymotoros.client.state import DEFAULT_STATE_TIMEOUT_S, JointState, Listener, RobotState
from pymotoros.client.state_view import StateView
from pymotoros.client.streaming import DEFAULT_GOAL_TOLERANCE
from pymotoros.client.tools import DEFAULT_TCP_SPEED_MM_S
from pymotoros.models import RobotModel
from pymotoros.models.s1cxg import S1cxgTable
from pymotoros.protocol.messages import DhLink, MotoMotionReply, Ping, PingReply, WireMessage


@dataclass(frozen=True, slots=True)
class ClientParts:
    """The parts a :class:`~pymotoros.client.RobotClient` is built of (its calls use them)."""

    view: StateView
    commands: MotionCommands
    io: IoPort
    motion: Motion
    geometry: Geometry
    robot: RobotModel


class RobotCalls:
    """The calls of a robot client, each defined once (see the module's documentation).

    On :class:`~pymotoros.client.RobotClient` a coroutine method here is awaited; on
    :class:`~pymotoros.client.SyncRobotClient` it blocks until done and returns the
    same result.
    """

    _parts: ClientParts

    # ------------------------------------------------------------------ state

    @facade_plain
    def feedback(self, group: int = 0) -> JointState | None:
        """The latest joint feedback of ``group`` (None before the first)."""
        return self._parts.view.feedback(group)

    @facade_plain
    def add_listener(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(state)`` on every state message; returns the function that removes it."""
        return self._parts.view.add_listener(listener)

    @blocking_twin
    async def wait_for_state(self, timeout_s: float = DEFAULT_STATE_TIMEOUT_S) -> RobotState:
        """Wait for a full state cycle: ROBOT_STATUS and every group's feedback.

        The groups the controller streams are checked against the robot model: other
        groups, or more axes than the model has, raise :class:`ModelMismatchError`.
        """
        return await self._parts.view.wait_for_state(timeout_s)

    @blocking_twin
    async def wait_until(
        self, predicate: Callable[[RobotState], bool], timeout_s: float, what: str = "the condition"
    ) -> RobotState:
        """Wait until ``predicate(state)`` holds (checked on every state message)."""
        return await self._parts.view.wait_until(predicate, timeout_s, what)

    @facade_plain
    def check_groups(self) -> None:
        """Compare the groups seen on the state stream with the robot model (no-op before)."""
        self._parts.view.check_groups()

    @blocking_twin
    async def check_dh_parameters(self) -> None:
        """Compare the controller's DH parameters (MOTO_GET_DH_PARAMETERS) with the model's.

        Two models with the same groups and axes (HC10 and GP12) look the same on the
        state stream; their DH parameters differ. Raises :class:`ModelMismatchError`
        naming the first difference, and the known robot whose parameters match. Opt-in:
        on a MotoROS whose library fails the request the connection is closed (§5.9).
        """
        return await self._parts.view.check_dh_parameters()

    @facade_plain
    def group_index(self, group: int | str) -> int:
        """The number of a group given by number (0, 1 …) or name (R1, r2, B1 …)."""
        return self._parts.view.group_index(group)

    # ------------------------------------------------------------------ motion port

    @blocking_twin
    async def request_motion(
        self, message: WireMessage, *, timeout_s: float | None = None
    ) -> MotoMotionReply:
        """Send a motion-port request answered by a MOTO_MOTION_REPLY; returns it as is."""
        return await self._parts.commands.request_motion(message, timeout_s=timeout_s)

    @blocking_twin
    async def check_motion_ready(self) -> MotionReadiness:
        """CHECK_MOTION_READY: ready, or the NOT_READY reason (never raises for "not ready")."""
        return await self._parts.commands.check_motion_ready()

    @blocking_twin
    async def start_trajectory_mode(self) -> None:
        """START_TRAJ_MODE: servo on, start INIT_ROS, wait until motion is possible.

        Raises :class:`NotReadyError` (``.reason``) when the controller cannot get there.
        """
        return await self._parts.commands.start_trajectory_mode()

    @blocking_twin
    async def stop_trajectory_mode(self) -> None:
        """STOP_TRAJ_MODE: end the INIT_ROS job (fails while motion is queued)."""
        await self._parts.commands.stop_trajectory_mode()

    @blocking_twin
    async def enable(self) -> None:
        """START_TRAJ_MODE (as :meth:`start_trajectory_mode`): the robot takes trajectory points."""
        await self._parts.commands.start_trajectory_mode()

    @blocking_twin
    async def disable(self) -> None:
        """STOP_TRAJ_MODE (as :meth:`stop_trajectory_mode`): the robot leaves trajectory mode."""
        await self._parts.commands.stop_trajectory_mode()

    @blocking_twin
    async def start_servos(self) -> None:
        """START_SERVOS: servo power on (the job is not started)."""
        await self._parts.commands.start_servos()

    @blocking_twin
    async def stop_servos(self) -> None:
        """STOP_SERVOS: servo power off."""
        await self._parts.commands.stop_servos()

    @blocking_twin
    async def reset_alarm(self) -> None:
        """RESET_ALARM: reset alarms and cancel errors (not waited on by MotoROS)."""
        await self._parts.commands.reset_alarm()

    @blocking_twin
    async def stop_motion(self) -> None:
        """STOP_MOTION: stop at once and clear every queue (no ramp from MotoROS)."""
        await self._parts.commands.stop_motion()

    @blocking_twin
    async def queue_count(self, group: int = 0) -> int:
        """Increments still queued for ``group`` (CHECK_QUEUE_CNT: the count is the subcode)."""
        return await self._parts.commands.queue_count(group)

    @blocking_twin
    async def select_tool(self, tool: int, group: int = 0) -> None:
        """MOTO_SELECT_TOOL: the tool file ``group`` moves with from its next segment on.

        The client's Cartesian operations use this tool's TCP from then on (MotoROS
        cannot report the selected tool, so the client remembers what it sent).
        """
        return await self._parts.commands.select_tool(tool, group)

    @blocking_twin
    async def get_dh_parameters(self) -> tuple[tuple[DhLink, ...], ...]:
        """DH parameters (theta, d, a, alpha) of each of the robot's groups."""
        return await self._parts.commands.get_dh_parameters()

    @blocking_twin
    async def ping(self) -> float:
        """PING on the motion port; returns the round trip in seconds."""
        start = time.perf_counter()
        await self._parts.commands.exchange(Ping(), PingReply)
        return time.perf_counter() - start

    # ------------------------------------------------------------------ IO

    @blocking_twin
    async def read_io_bit(self, address: int, *, check: bool = True) -> int:
        """Read one IO bit (e.g. 10010 = general output OT#1)."""
        return await self._parts.io.read_io_bit(address, check=check)

    @blocking_twin
    async def write_io_bit(self, address: int, value: int, *, check: bool = True) -> None:
        """Write one IO bit (general outputs, network inputs, interface panel only)."""
        await self._parts.io.write_io_bit(address, value, check=check)

    @blocking_twin
    async def read_io_group(self, address: int, *, check: bool = True) -> int:
        """Read 8 bits; ``address`` is the byte number (1001 = bits 10010..10017)."""
        return await self._parts.io.read_io_group(address, check=check)

    @blocking_twin
    async def write_io_group(self, address: int, value: int, *, check: bool = True) -> None:
        """Write 8 bits (0..255, bit 0 first) to byte ``address``."""
        await self._parts.io.write_io_group(address, value, check=check)

    @blocking_twin
    async def read_mregister(self, number: int, *, check: bool = True) -> int:
        """Read M-register ``number`` (0..999; IO port only)."""
        return await self._parts.io.read_mregister(number, check=check)

    @blocking_twin
    async def write_mregister(self, number: int, value: int, *, check: bool = True) -> None:
        """Write M-register ``number`` (0..559) with 0..65535 (IO port only)."""
        await self._parts.io.write_mregister(number, value, check=check)

    # ------------------------------------------------------------------ motion

    @facade_plain
    def limits(self, group: int | str = 0) -> JointLimits:
        """Planning limits of ``group`` from the robot model."""
        return self._parts.motion.limits(group)

    @blocking_twin
    async def current_positions(
        self, group: int | Sequence[int] = 0, *, at_rest: bool = True, timeout_s: float = 10.0
    ) -> tuple[float, ...]:
        """Joint positions from feedback; with ``at_rest``, once the robot is settled."""
        return await self._parts.motion.current_positions(
            group, at_rest=at_rest, timeout_s=timeout_s
        )

    @facade_plain
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
        return self._parts.motion.plan(
            start,
            goal,
            groups=groups,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            sample_period=sample_period,
            avoid=avoid,
            tool=tool,
        )

    @blocking_twin
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
        return await self._parts.motion.execute(
            trajectory,
            groups=groups,
            busy_timeout_s=busy_timeout_s,
            goal_tolerance=goal_tolerance,
            timeout_s=timeout_s,
            check_speed=check_speed,
            on_progress=on_progress,
            force=force,
            tool=tool,
        )

    @facade_plain
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
        return self._parts.motion.guard(trajectory, groups, tool)

    @blocking_twin
    async def stop(self) -> None:
        """Stop the robot now (STOP_MOTION) and end a move running in another task.

        Safe from another task of the client's loop while :meth:`execute` /
        :meth:`move_joints` runs: that call raises :class:`MoveStoppedError`. From
        another thread use :meth:`stop_threadsafe`.
        """
        return await self._parts.motion.stop()

    @facade_plain
    def stop_threadsafe(self, timeout_s: float = DEFAULT_REQUEST_TIMEOUT_S) -> None:
        """:meth:`stop` from another thread (not the client's loop); waits for the reply."""
        self._parts.motion.stop_threadsafe(timeout_s)

    @blocking_twin
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
        return await self._parts.motion.move_joints(
            goal,
            group=group,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
            goal_tolerance=goal_tolerance,
            busy_timeout_s=busy_timeout_s,
            timeout_s=timeout_s,
            avoid=avoid,
            force=force,
            tool=tool,
        )

    @facade_plain
    def named_pose(
        self, name: str, *, srdf: str | Path | None = None, group: int | str = 0
    ) -> tuple[float, ...]:
        """Joint values of a named pose: an SRDF ``group_state`` or the built-in ``home``."""
        return self._parts.motion.named_pose(name, srdf=srdf, group=group)

    @blocking_twin
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
        return await self._parts.motion.move_named(
            name,
            srdf=srdf,
            group=group,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
            force=force,
        )

    # ------------------------------------------------------------------ geometry

    @after_first_state
    def tcp_pose(
        self,
        group: int = 0,
        *,
        frame: Literal["flange", "tool0", "tcp"] = "tcp",
        reference: Literal["base", "base_link"] = "base",
        tool: int | None = None,
    ) -> Pose:
        """The TCP of the tool in force (or of ``tool``) from the latest joint feedback:
        (x, y, z, rx, ry, rz) in m and rad, R = Rz·Ry·Rx, in base coordinates
        (``reference="base_link"``: the mounting surface). Raises ClientError before the
        first feedback has arrived, :class:`ToolUnknownError` when the tool is unknown."""
        return self._parts.geometry.tcp_pose(group, frame=frame, reference=reference, tool=tool)

    @blocking_twin
    async def move_linear(
        self,
        pose: Sequence[float],
        *,
        group: int = 0,
        tcp_speed_mm_s: float = DEFAULT_TCP_SPEED_MM_S,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        timeout_s: float | None = None,
        tool: int | None = None,
        force: bool = False,
    ) -> MoveResult:
        """Move the TCP of the tool in force (or of ``tool``) in a straight line to ``pose``
        = (x, y, z, rx, ry, rz) in base coordinates (m, rad, R = Rz·Ry·Rx), at most
        ``tcp_speed_mm_s`` and within every joint limit (scaled as :meth:`move_joints`).
        A line through a singularity, out of reach or past a joint limit is refused before
        anything is sent (:class:`PlanningError` with the joint and the numbers); so is a
        line that would touch an obstacle of the client's cell file
        (:class:`~pymotoros.errors.PathBlockedError`, unless ``force``)."""
        with self._parts.motion.one_move("move_linear"):
            return await self._parts.geometry.move_linear(
                pose,
                group=group,
                tcp_speed_mm_s=tcp_speed_mm_s,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                on_progress=on_progress,
                timeout_s=timeout_s,
                tool=tool,
                force=force,
            )

    @blocking_twin
    async def move_pose(
        self,
        pose: Sequence[float],
        *,
        group: int = 0,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        tool: int | None = None,
        avoid: bool = False,
        force: bool = False,
    ) -> MoveResult:
        """A joint move to the joint values nearest the current ones that put the TCP of
        the tool in force (or of ``tool``) at ``pose`` (base coordinates): not a straight
        line (see :meth:`move_linear`). Checked against the obstacles of the client's cell
        file as :meth:`move_joints` is (``force`` skips the check); ``avoid``: around
        them (a goal pose in collision is a :class:`~pymotoros.errors.PathBlockedError`
        naming the obstacle)."""
        with self._parts.motion.one_move("move_pose"):
            return await self._parts.geometry.move_pose(
                pose,
                group=group,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                on_progress=on_progress,
                tool=tool,
                avoid=avoid,
                force=force,
            )

    @blocking_twin
    async def move_relative(
        self,
        dx: float = 0.0,
        dy: float = 0.0,
        dz: float = 0.0,
        drx: float = 0.0,
        dry: float = 0.0,
        drz: float = 0.0,
        *,
        frame: CartesianFrame = "base",
        group: int = 0,
        linear: bool = True,
        tcp_speed_mm_s: float = DEFAULT_TCP_SPEED_MM_S,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        tool: int | None = None,
        force: bool = False,
    ) -> MoveResult:
        """Move the TCP by (dx, dy, dz) m and (drx, dry, drz) rad in the ``base`` frame or
        the ``tool`` frame, in a straight line (``linear=False``: a joint move); checked
        against the cell's obstacles as every move (``force`` skips the check)."""
        with self._parts.motion.one_move("move_relative"):
            return await self._parts.geometry.move_relative(
                dx,
                dy,
                dz,
                drx,
                dry,
                drz,
                frame=frame,
                group=group,
                linear=linear,
                tcp_speed_mm_s=tcp_speed_mm_s,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                on_progress=on_progress,
                tool=tool,
                force=force,
            )

    @blocking_twin
    async def move_cartesian(
        self,
        pose: Sequence[float],
        *,
        group: int = 0,
        linear: bool = False,
        tcp_speed_mm_s: float = DEFAULT_TCP_SPEED_MM_S,
        speed_scale: float = 1.0,
        accel_scale: float = 1.0,
        on_progress: Callable[[FollowingSample], None] | None = None,
        tool: int | None = None,
        avoid: bool = False,
        force: bool = False,
    ) -> MoveResult:
        """The TCP to ``pose``: a straight line with ``linear`` (:meth:`move_linear`), else
        a joint move (:meth:`move_pose`, around the obstacles with ``avoid``). The one
        place that chooses between the two."""
        with self._parts.motion.one_move("move_cartesian"):
            return await self._parts.geometry.move_cartesian(
                pose,
                group=group,
                linear=linear,
                tcp_speed_mm_s=tcp_speed_mm_s,
                speed_scale=speed_scale,
                accel_scale=accel_scale,
                on_progress=on_progress,
                tool=tool,
                avoid=avoid,
                force=force,
            )

    # ------------------------------------------------------------------ registers

    @blocking_twin
    async def read_register_outputs(
        self, table: S1cxgTable | Mapping[str, object] | str | Path, group: int = 0
    ) -> RegisterValues:
        """The S1CxG register outputs (TCP speed, Cartesian position, axis speeds and
        positions, pulses) decoded with ``table``: an :class:`S1cxgTable`, a
        ``{"330": 1, ...}`` mapping or a cell file with ``[groups.s1cxg]``."""
        model = self._parts.robot.groups[group]
        if not isinstance(table, S1cxgTable):
            table = s1cxg_table(table, model, index=group)
        return await read_register_outputs(self._parts.io.read_mregister, table, model)
