"""Trajectory points (reference §3.4, §3.5), SELECT_TOOL (§5.8) and GET_DH_PARAMETERS (§5.9).

:class:`TrajectoryPoints` validates JOINT_TRAJ_PT_FULL (14) and JOINT_TRAJ_PT_FULL_EX
(2016) in MotoROS's order and hands accepted points to the group's interpolator.
Where the real code has an outright bug we do the safe thing (see
``docs/fidelity.md``); quirks clients may rely on are kept.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Final

from pymotoros.controller.api import Outcome, PointData
from pymotoros.controller.commands import MotionCommands
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.processes import Process
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.replies import SUCCESS, invalid, reply
from pymotoros.models.rules import MAX_POINT_TIME_S, f32
from pymotoros.motion import (
    Refusal,
    TrajPoint,
    check_speed,
    check_start,
    check_time,
)
from pymotoros.motion.constants import SLOTS
from pymotoros.motion.points import GroupPoint
from pymotoros.protocol.constants import (
    MAX_DH_LINKS,
    MAX_GROUPS,
    MAX_TOOL_NUMBER,
    REQUIRED_POINT_FIELDS,
    InvalidSubcode,
    ResultCode,
)

logger = logging.getLogger(__name__)

REQUIRED_FIELDS: Final = int(REQUIRED_POINT_FIELDS)
"""time | position | velocity (7), as a plain int (IntFlag arithmetic is slow)."""

DhTable = tuple[tuple[tuple[float, float, float, float], ...], ...]


class TrajectoryPoints:
    """Validation and acceptance of trajectory points; the tool and DH requests."""

    def __init__(self, ctx: MotoRosContext, readiness: Readiness, commands: MotionCommands) -> None:
        cell = ctx.cell
        self._cell = cell
        self._machine = ctx.machine
        self._readiness = readiness
        self._flags = readiness.flags  # motion_ready, read every tick / every point
        self._commands = commands
        self._axes = ctx.axes
        self._interpolators = ctx.interpolators
        self._servos = ctx.servos
        self._num_groups = len(self._axes)
        self._sets_jog_tool = cell.controller.sets_jog_tool
        self.jog_tool = [0] * self._num_groups
        """The pendant's jog tool per group (SELECT_TOOL sets it, except on FS100)."""
        self._float_modes = tuple(a.float_mode for a in self._axes)
        self._speed_limits = tuple(a.max_speed[: a.num_axes] for a in self._axes)
        """Per group, check_speed's limit of each axis (ROS order): a velocity within
        it is neither refused nor logged."""
        self._lowest_limit = tuple(min(limits) for limits in self._speed_limits)
        self._busy_replies = tuple(
            reply(
                ResultCode.BUSY,
                detail=f"group {g}: the previous point is still being interpolated; send it again",
            )
            for g in range(self._num_groups)
        )

    # ================================================================== trajectory points

    def _to_traj(self, point: PointData) -> TrajPoint:
        return TrajPoint(point.time, tuple(point.pos[:SLOTS]), tuple(point.vel[:SLOTS]))

    def _refused(self, refusal: Refusal, point_desc: str, group_no: int | None = None) -> Outcome:
        return invalid(int(refusal.subcode), f"{point_desc}: {refusal.message}", group_no)

    def trajectory_point(self, sequence: int, point: PointData) -> Outcome | Process:
        """JOINT_TRAJ_PT_FULL (14): §3.4, in its order.

        An :class:`Outcome` at once, except a start (sequence 0) in ECO mode, which must
        first re-enable the servos: that one is a Process. A client streams one point
        per period at dense spacing, so this is the intake's hot path: a point that is
        accepted or answered BUSY builds nothing but its float32 form, made once (the
        speed check reads its velocities).
        """
        if not self._flags.motion_ready:
            return self._readiness.not_ready()
        g = point.group_no
        if not 0 <= g < self._num_groups:
            return self._bad_group(g)
        if point.valid_fields & REQUIRED_FIELDS != REQUIRED_FIELDS:
            return self._insufficient(point)
        if not f32(point.time) < MAX_POINT_TIME_S:  # also NaN: check_time words it
            refusal = check_time(self._to_traj(point))
            if refusal is not None:
                return self._refused(refusal, f"point {sequence} of group {g}")
        if sequence > 0:
            return self._queue_point(g, point, sequence)
        if sequence == 0:
            traj = self._to_traj(point)
            if self._machine.state.eco:
                return self._start_after_eco(g, traj)
            return self._start_group(g, traj, sequence)
        return self._bad_sequence(sequence)

    def _start_after_eco(self, g: int, traj: TrajPoint) -> Process:
        """Sequence 0 in ECO mode: the servos come back first (§4.5), then the start."""
        yield from self._commands.eco_reenable()
        return self._start_group(g, traj, 0)

    def trajectory_point_ex(self, sequence: int, points: Sequence[PointData]) -> Process:
        """MOTO_JOINT_TRAJ_PT_FULL_EX (2016): §3.5, in its order."""
        if not points:
            return invalid(
                InvalidSubcode.DATA,
                "JOINT_TRAJ_PT_FULL_EX with no group; MotoROS 1.9.12 would resend its "
                "previous reply, we answer 3010 INVALID_DATA",
                -1,
            )
        if not self._flags.motion_ready:
            return self._readiness.not_ready(group_no=points[-1].group_no)
        for p in points:
            g = p.group_no
            if not 0 <= g < self._num_groups:
                return self._bad_group(g, group_no=g)
            if self._interpolators[g].pending:
                return self._busy(g, sequence, group_no=g)
            if p.valid_fields & REQUIRED_FIELDS != REQUIRED_FIELDS:
                return self._insufficient(p, group_no=g)
        last = points[-1].group_no
        for p in points:
            g = p.group_no
            if sequence == 0:
                if self._machine.state.eco:
                    yield from self._commands.eco_reenable()
                outcome = self._start_group(g, self._to_traj(p), sequence, group_no=g)
            elif sequence > 0:
                outcome = self._queue_point(g, p, sequence, group_no=g)
            else:
                return self._bad_sequence(sequence, group_no=g)
            if not outcome.ok:
                return outcome
        return reply(ResultCode.SUCCESS, group_no=last)

    def _bad_group(self, g: int, group_no: int | None = None) -> Outcome:
        n = self._num_groups
        detail = f"group {g} does not exist ({n} group(s): 0..{n - 1})"
        return invalid(InvalidSubcode.GROUPNO, detail, group_no)

    def _insufficient(self, point: PointData, group_no: int | None = None) -> Outcome:
        return invalid(
            InvalidSubcode.DATA_INSUFFICIENT,
            f"group {point.group_no}: valid_fields {point.valid_fields} lacks "
            "time (1), position (2) or velocity (4); MotoROS needs all three",
            group_no,
        )

    def _bad_sequence(self, sequence: int, group_no: int | None = None) -> Outcome:
        detail = f"sequence {sequence} is negative; a trajectory starts at 0"
        return invalid(InvalidSubcode.SEQUENCE, detail, group_no)

    def _busy(self, g: int, sequence: int, group_no: int | None = None) -> Outcome:
        if group_no is None:
            return self._busy_replies[g]
        return reply(ResultCode.BUSY, detail=self._busy_replies[g].detail, group_no=group_no)

    def _start_group(
        self, g: int, traj: TrajPoint, sequence: int, group_no: int | None = None
    ) -> Outcome:
        """Sequence 0: initialise the group, then the interleaved start/speed checks."""
        interp = self._interpolators[g]
        queued = len(interp.queue)
        if queued or interp.pending:
            logger.warning(
                "group %d: trajectory start (sequence 0) while %d increments are queued%s; "
                "MotoROS makes no BUSY check here and re-initialises the group, the queued "
                "motion still runs",
                g,
                queued,
                " and a point is pending" if interp.pending else "",
            )
        commanded = tuple(self._servos[g].command)
        interp.start(traj, commanded)
        refusal = check_start(traj, commanded, self._axes[g])
        if refusal is not None:
            return self._refused(refusal, f"point 0 of group {g}", group_no=group_no)
        return reply(ResultCode.SUCCESS, group_no=group_no)

    def _queue_point(
        self, g: int, point: PointData, sequence: int, group_no: int | None = None
    ) -> Outcome:
        """Sequence > 0: BUSY while a point is pending, then the speed check (§3.4 step 6)."""
        interp = self._interpolators[g]
        if interp.pending:  # type 14's BUSY (no group number) is made once: no call
            return self._busy_replies[g] if group_no is None else self._busy(g, sequence, group_no)
        ready = GroupPoint.from_values(
            point.time, point.pos[:SLOTS], point.vel[:SLOTS], self._float_modes[g]
        )
        # Within the lowest limit (tame: no NaN, which max() could pass over), nothing to
        # refuse or log; otherwise check_speed decides, axis by axis, and may log.
        if not (ready.tame and max(map(abs, ready.vel)) <= self._lowest_limit[g]):
            refusal = check_speed(self._to_traj(point), self._axes[g])
            if refusal is not None:
                return self._refused(refusal, f"point {sequence} of group {g}", group_no=group_no)
        interp.set_pending_point(ready)
        return SUCCESS if group_no is None else reply(ResultCode.SUCCESS, group_no=group_no)

    # ================================================================== tools and DH

    def select_tool(self, group_no: int, tool: int) -> Outcome:
        """SELECT_TOOL (§5.8)."""
        if not 0 <= group_no < self._num_groups:
            return self._bad_group(group_no)
        if not 0 <= tool <= MAX_TOOL_NUMBER:
            detail = f"tool {tool} is outside 0..{MAX_TOOL_NUMBER}"
            return invalid(InvalidSubcode.DATA_TOOLNO, detail)
        self._interpolators[group_no].tool = tool
        if self._sets_jog_tool:
            self.jog_tool[group_no] = tool
        return SUCCESS

    def dh_parameters(self) -> DhTable:
        """GET_DH_PARAMETERS (§5.9): 4 groups × 8 links × (theta, d, a, alpha)."""
        zero = (0.0, 0.0, 0.0, 0.0)
        table = []
        for g in range(MAX_GROUPS):
            links: list[tuple[float, float, float, float]] = []
            if g < self._num_groups:
                model = self._cell.groups[g]
                links = [(d.theta, d.d, d.a, d.alpha) for d in model.dh]
            links += [zero] * (MAX_DH_LINKS - len(links))
            table.append(tuple(links))
        return tuple(table)
