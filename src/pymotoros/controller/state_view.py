"""What the state server and the snapshot read: feedback, status, in-motion, per-group state.

:class:`StateView` converts the servos' pulses to ROS units (reference §2.4), answers
ROBOT_STATUS from the status monitor's last reading (§2.6) and builds each group's part
of the operator's snapshot. It only reads; nothing here changes the controller.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from pymotoros.controller.api import FeedbackData, GroupSnapshot, StatusData
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.servo import IN_MOTION_PULSES, ZERO_INCREMENT
from pymotoros.controller.tool_point import TcpTracker
from pymotoros.controller.units import RosConverter
from pymotoros.protocol.constants import MAX_JOINTS, StatusMode, ValidFields

FEEDBACK_FIELDS: Final = int(ValidFields.POSITION | ValidFields.VELOCITY)
"""JOINT_FEEDBACK validFields: position and velocity, never time (§2.4)."""


def _pad(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(values) + (0.0,) * (MAX_JOINTS - len(values))


class StateView:
    """Joint feedback, robot status and group snapshots of one controller."""

    def __init__(self, ctx: MotoRosContext, readiness: Readiness, tcp: TcpTracker) -> None:
        self._ctx = ctx
        self._readiness = readiness
        self._tcp = tcp
        self._to_ros = tuple(RosConverter(a) for a in ctx.axes)
        self._at_rest: list[tuple[tuple[int, ...], FeedbackData] | None] = [None] * len(ctx.axes)
        """Per group: the command pulses of the last feedback computed at rest, and it."""

    def check_group(self, group_no: int) -> None:
        """ValueError naming the valid range when ``group_no`` is not a group of the cell."""
        count = self._ctx.num_groups
        if not 0 <= group_no < count:
            raise ValueError(f"group {group_no} does not exist (0..{count - 1})")

    def commanded_pulses(self, group_no: int) -> tuple[int, ...]:
        """The group's command register: pulses, controller order, 8 slots."""
        self.check_group(group_no)
        return tuple(self._ctx.servos[group_no].command)

    def joint_feedback(self, group_no: int) -> FeedbackData:
        """§2.4: feedback pulses → rad (m), ROS order; speed from the servo model."""
        self.check_group(group_no)
        ctx = self._ctx
        servo = ctx.servos[group_no]
        powered = ctx.machine.state.drives_powered
        if servo.at_rest(powered):
            # Feedback = command and speed = 0 until the command changes: a robot at rest
            # (most of a test's state cycles) reuses the last conversion.
            command = tuple(servo.command)
            rest = self._at_rest[group_no]
            if rest is not None and rest[0] == command:
                return rest[1]
            data = self._feedback(group_no, command, ZERO_INCREMENT)
            self._at_rest[group_no] = (command, data)
            return data
        return self._feedback(
            group_no, servo.feedback(ctx.clock.tick_count, powered), servo.speed()
        )

    def _feedback(
        self, group_no: int, pulses: Sequence[int], speed: Sequence[int]
    ) -> FeedbackData:
        to_ros = self._to_ros[group_no]
        return FeedbackData(group_no, FEEDBACK_FIELDS, _pad(to_ros(pulses)), _pad(to_ros(speed)))

    def in_motion(self) -> bool:
        """Any queue holds increments, or |feedback − command| > 30 pulses on a valid axis."""
        ctx = self._ctx
        if ctx.queues.has_queued_motion():
            return True
        powered = ctx.machine.state.drives_powered
        tick = ctx.clock.tick_count
        for axes, servo in zip(ctx.axes, ctx.servos, strict=True):
            if servo.settled():  # feedback = command (± noise of at most 10 pulses)
                continue
            fb = servo.feedback(tick, powered)
            cmd = servo.command
            for slot, valid in enumerate(axes.valid):
                if valid and abs(fb[slot] - cmd[slot]) > IN_MOTION_PULSES:
                    return True
        return False

    def robot_status(self) -> StatusData:
        """§2.6, from the status monitor's last reading."""
        readiness = self._readiness
        r = readiness.reading
        return StatusData(
            drives_powered=int(bool(r.servo) and not r.eco),
            e_stopped=int(r.estopped),
            error_code=readiness.monitor.error_code,
            in_error=int(r.in_error),
            in_motion=int(self.in_motion()),
            mode=int(StatusMode.encode(bool(r.play))),
            motion_possible=int(readiness.motion_ready),
        )

    def group_snapshots(self) -> tuple[GroupSnapshot, ...]:
        """Every group's joints (rad), command pulses, queue, tool and TCP, in group order."""
        return tuple(self.group_snapshot(g) for g in range(self._ctx.num_groups))

    def group_snapshot(self, g: int) -> GroupSnapshot:
        ctx = self._ctx
        axes, servo, interp = ctx.axes[g], ctx.servos[g], ctx.interpolators[g]
        to_ros = self._to_ros[g]
        n = axes.num_axes
        cmd = servo.command
        command_rad = to_ros(cmd)[:n]
        powered = ctx.machine.state.drives_powered
        feedback_rad = to_ros(servo.feedback(ctx.clock.tick_count, powered))[:n]
        period_ms = ctx.clock.period_ms
        return GroupSnapshot(
            name=ctx.cell.groups[g].name,
            joint_names=axes.joint_names,
            command_rad=command_rad,
            feedback_rad=feedback_rad,
            command_pulse=tuple(cmd[axes.ros_to_slot[i]] for i in range(n)),
            queue=len(interp.queue),
            tool=interp.tool,
            tcp=self._tcp.snapshot(
                g,
                interp.tool,
                command_rad,
                feedback_rad,
                [v * 1000.0 / period_ms for v in to_ros(servo.last_increment)[:n]],
                to_ros(servo.speed())[:n],
            ),
        )
