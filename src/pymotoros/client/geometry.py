"""Where the tool is, and Cartesian moves: the geometry part of ``RobotClient``.

Every pose here is the TCP of the tool in force (:mod:`pymotoros.client.tools`): the
client plans and reports with that tool's offset on ``tool0``, and refuses when it
cannot know which tool that is. MotoROS only takes joint trajectories, so a pose
becomes joint values by inverse kinematics (:meth:`Geometry.move_pose`) or a straight
TCP line (:meth:`Geometry.move_linear`, :mod:`pymotoros.client.cartesian`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal

from pymotoros.client.errors import ClientError
from pymotoros.client.following import FollowingSample
from pymotoros.client.motion import Motion
from pymotoros.client.move_result import MoveResult
from pymotoros.client.planning import PlanningError
from pymotoros.client.state_view import StateView
from pymotoros.client.tools import DEFAULT_TCP_SPEED_MM_S, ToolTable
from pymotoros.errors import KinematicsError

Pose = tuple[float, float, float, float, float, float]
CartesianFrame = Literal["base", "tool"]


class Geometry:
    """TCP poses from the feedback and moves to TCP poses, with the tool in force."""

    def __init__(self, view: StateView, motion: Motion, tools: ToolTable) -> None:
        self._view = view
        self._motion = motion
        self._tools = tools

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
        positions = self._view.state.positions(group)
        if positions is None:
            raise ClientError(f"no joint feedback for group {group} yet: wait_for_state() first")
        if frame != "tcp":  # flange and tool0 do not depend on the tool
            tool = 0 if tool is None else tool
        return self._tools.chain(group, tool).pose(positions, frame, reference)

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
        from pymotoros.client.cartesian import plan_linear_move  # numpy, Pinocchio: lazily

        chain = self._tools.chain(group, tool)  # an unknown tool is refused before waiting
        start = await self._motion.current_positions(group)
        trajectory = plan_linear_move(
            chain,
            start,
            pose,
            self._motion.limits(group),
            tcp_speed_mm_s=tcp_speed_mm_s,
            velocity_scaling=speed_scale,
            acceleration_scaling=accel_scale,
        )
        return await self._motion.execute(
            trajectory,
            groups=(group,),
            on_progress=on_progress,
            timeout_s=timeout_s,
            force=force,
            tool=tool,
        )

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
        chain = self._tools.chain(group, tool)
        start = await self._motion.current_positions(group)
        try:
            goal = chain.ik(pose, start).q
        except KinematicsError as exc:
            raise PlanningError(f"cannot reach the pose: {exc}") from None
        return await self._motion.move_joints(
            tuple(goal.tolist()),
            group=group,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
            avoid=avoid,
            force=force,
            tool=tool,
        )

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
        from pymotoros.client.cartesian import relative_target
        from pymotoros.kinematics import matrix_to_pose

        chain = self._tools.chain(group, tool)
        start = await self._motion.current_positions(group)
        delta = (dx, dy, dz, drx, dry, drz)
        target = matrix_to_pose(relative_target(chain.fk(start), delta, frame))
        return await self.move_cartesian(
            target, group=group, linear=linear, tcp_speed_mm_s=tcp_speed_mm_s,
            speed_scale=speed_scale, accel_scale=accel_scale, on_progress=on_progress, tool=tool,
            force=force,
        )  # fmt: skip

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
        options: dict[str, Any] = {
            "group": group, "speed_scale": speed_scale, "accel_scale": accel_scale,
            "on_progress": on_progress, "tool": tool, "force": force,
        }  # fmt: skip
        if linear:
            if avoid:
                raise PlanningError(
                    "avoid plans a joint move around the obstacles; a straight line cannot "
                    "go around them: move to the pose with linear=False (--pose without "
                    "--linear)"
                )
            return await self.move_linear(pose, tcp_speed_mm_s=tcp_speed_mm_s, **options)
        return await self.move_pose(pose, avoid=avoid, **options)
