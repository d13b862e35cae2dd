"""MOTO_MOTION_CTRL (reference §3.1–§3.3): every command, as a process.

Commands that wait (START_TRAJ_MODE polls every 50 ms for up to 5 s …) are
generators run by :class:`~pymotoros.controller.processes.Scheduler`. They drive the
controller only through what MotoPlus offers MotoROS: servo on/off, alarm reset,
error cancel, job start and the OT#890 output.
"""

from __future__ import annotations

import logging
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.api import Outcome
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.machine import Event, ServoPower
from pymotoros.controller.polling import POLL_LIMIT_MS, Waiting, wait_until
from pymotoros.controller.processes import Process
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.replies import SUCCESS, reply
from pymotoros.controller.stop_motion import stop_motion
from pymotoros.protocol.constants import InvalidSubcode, MotionCommand, ResultCode

logger = logging.getLogger(__name__)

ECO_REENABLE_SLEEP_MS: Final = 100
"""The sequence-0 eco-mode re-enable sleeps 100 ms after each step (§3.4 step 5.1)."""
INIT_ROS: Final = "INIT_ROS"
QUEUE_COUNT_FAILURE: Final = -1
"""CHECK_QUEUE_CNT's subcode for an invalid group (§3.1)."""


class MotionCommands:
    """MOTO_MOTION_CTRL processing: trajectory mode, servos, alarm reset, stop, queue count."""

    def __init__(self, ctx: MotoRosContext, readiness: Readiness) -> None:
        self._clock = ctx.clock
        self._io = ctx.io
        self._machine = ctx.machine
        self._readiness = readiness
        self._queues = ctx.queues
        self._axes = ctx.axes
        self._num_groups = len(self._axes)

    def motion_ctrl(self, group_no: int, command: int) -> Process:
        """One MOTO_MOTION_CTRL request, as a process."""
        if command == MotionCommand.CHECK_MOTION_READY:
            readiness = self._readiness
            return SUCCESS if readiness.motion_ready else readiness.not_ready(ResultCode.FALSE)
        if command == MotionCommand.CHECK_QUEUE_CNT:
            if not 0 <= group_no < self._num_groups:
                return reply(
                    ResultCode.FAILURE,
                    QUEUE_COUNT_FAILURE,
                    f"CHECK_QUEUE_CNT: group {group_no} does not exist "
                    f"({self._num_groups} group(s): 0..{self._num_groups - 1})",
                )
            return reply(ResultCode.SUCCESS, len(self._queues.interpolators[group_no].queue))
        if command == MotionCommand.STOP_MOTION:
            return (yield from self._stop_motion())
        if command == MotionCommand.START_SERVOS:
            return (yield from self._start_servos())
        if command == MotionCommand.STOP_SERVOS:
            return (yield from self._stop_servos())
        if command == MotionCommand.RESET_ALARM:
            return self._reset_alarm()
        if command == MotionCommand.START_TRAJ_MODE:
            return (yield from self.start_traj_mode())
        if command == MotionCommand.STOP_TRAJ_MODE:
            return (yield from self.stop_traj_mode())
        if command == MotionCommand.DISCONNECT:
            outcome = yield from self.stop_traj_mode()
            if outcome.ok:
                return reply(ResultCode.SUCCESS, close_connection=True)
            return outcome
        known = ", ".join(f"{c.name} {int(c)}" for c in MotionCommand)
        return reply(
            ResultCode.INVALID,
            InvalidSubcode.COMMAND,
            f"unknown MOTO_MOTION_CTRL command {command} (known: {known}); MotoROS 1.9.12 "
            "would resend its previous reply, we answer 3006 INVALID_COMMAND",
        )

    def _stop_motion(self) -> Process:
        return stop_motion(self._readiness, self._queues, self._clock)

    def _servo_is_on(self) -> bool:
        s = self._machine.state
        return s.servo_on and not s.eco

    def _servo_is_off(self) -> bool:
        return self._machine.state.servo is ServoPower.OFF

    def _leave_eco(self) -> Waiting:
        """Disable eco mode: servo OFF, then wait ≤ 5 s for 50727 to drop."""
        self._machine.fire(Event.SERVO_OFF, self._clock.time_ms)
        return (yield from wait_until(self._clock, lambda: not self._machine.state.eco))

    def _start_servos(self) -> Process:
        if self._machine.state.eco:
            yield from self._leave_eco()
        refused = self._machine.fire(Event.REQUEST_SERVO_ON, self._clock.time_ms)
        if (yield from wait_until(self._clock, self._servo_is_on)):
            return SUCCESS
        return reply(
            ResultCode.FAILURE,
            detail=f"servo power did not come on within {POLL_LIMIT_MS} ms"
            + (f" (servo on refused: {refused})" if refused else ""),
        )

    def _stop_servos(self) -> Process:
        stopped = yield from self._stop_motion()
        self._machine.fire(Event.SERVO_OFF, self._clock.time_ms)
        off = yield from wait_until(self._clock, self._servo_is_off)
        if stopped.ok and off:
            return SUCCESS
        return reply(ResultCode.FAILURE, detail=stopped.detail or "servo power stayed on")

    def _reset_alarm(self) -> Outcome:
        s = self._machine.state
        now = self._clock.time_ms
        if s.alarms:
            self._machine.fire(Event.RESET_ALARMS, now)
        if s.errors:
            self._machine.fire(Event.CANCEL_ERRORS, now)
        return SUCCESS

    def start_traj_mode(self) -> Process:
        """§3.2, step by step."""
        machine = self._machine
        readiness = self._readiness
        # 1. status update; clear the PFL and inc-move-error latches
        readiness.status_update()
        readiness.flags.clear_latches()
        # 2. already ready
        if readiness.motion_ready:
            return SUCCESS
        ok = self._prepare_for_job()
        if ok:
            ok = yield from self._power_up()
        if ok:
            # 8. clear leftover data; every group restarts from its commanded position
            if self._queues.has_queued_motion():
                self._queues.clear()
            # 9. start INIT_ROS, then wait for motion-ready
            refused = machine.fire(Event.START_JOB, self._clock.time_ms)
            if refused is None:
                yield from wait_until(self._clock, lambda: readiness.motion_ready)
            else:
                logger.info("START_TRAJ_MODE: cannot start %s: %s", INIT_ROS, refused)
        # 10. final check
        return self._final_check()

    def _final_check(self) -> Outcome:
        readiness = self._readiness
        readiness.status_update()
        if readiness.motion_ready:
            return SUCCESS
        return readiness.not_ready()

    def _prepare_for_job(self) -> bool:
        """Steps 3–6: refuse what needs an operator, cancel errors, reset alarms."""
        s = self._machine.state
        now = self._clock.time_ms
        readiness = self._readiness
        reading = readiness.reading
        if reading.operating:
            logger.info("START_TRAJ_MODE: another job is running; MotoROS does not interrupt it")
            return False
        if reading.estopped or reading.hold or not reading.remote:
            return False
        if reading.error:
            self._machine.fire(Event.CANCEL_ERRORS, now)
        if any(reading.alarm_bits) or s.alarms:
            self._machine.fire(Event.RESET_ALARMS, now)
            readiness.status_update()
            if readiness.reading.in_error:
                return False
        return True

    def _power_up(self) -> Waiting:
        """Step 7: leave eco mode, servo on, wait ≤ 5 s."""
        if self._servo_is_on():
            return True
        eco = self._machine.state.eco
        if eco:
            yield from self._leave_eco()
        refused = self._machine.fire(Event.REQUEST_SERVO_ON, self._clock.time_ms)
        if refused is not None:
            logger.info("START_TRAJ_MODE: servo on refused: %s", refused)
            return False
        return (yield from wait_until(self._clock, self._servo_is_on))

    def stop_traj_mode(self) -> Process:
        """§3.3: queues must be empty; StopMotion; OT#890 ON releases the job."""
        queues = self._queues
        if queues.has_queued_motion():
            counts = ", ".join(
                f"{a.name}: {len(i.queue)}"
                for a, i in zip(self._axes, queues.interpolators, strict=True)
            )
            return reply(
                ResultCode.FAILURE,
                detail=f"increments are still queued ({counts}); wait for the motion to end "
                "or send STOP_MOTION first",
            )
        stopped = yield from self._stop_motion()
        if not stopped.ok:
            return stopped
        self._io.set(signals.ROS_DONE, 1)
        return SUCCESS

    def eco_reenable(self) -> Process:
        """v1.9.12: sequence 0 in eco mode runs STOP_TRAJ_MODE and START_TRAJ_MODE."""
        logger.info("trajectory start in eco mode: leaving and re-entering trajectory mode")
        yield from self.stop_traj_mode()
        yield ECO_REENABLE_SLEEP_MS
        yield from self.start_traj_mode()
        yield ECO_REENABLE_SLEEP_MS
        return SUCCESS
