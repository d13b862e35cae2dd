"""MotoROS 1.9.12's logic on the virtual controller (reference §2–§6).

:class:`MotoRos` is what the MotoPlus application does: the 10 ms status monitor
and its queue-clearing edges, the motion-ready flag and the NOT_READY subcode
order, every MOTO_MOTION_CTRL command, the validation of trajectory points, the
IncMove task's send and failure paths, SELECT_TOOL, GET_DH_PARAMETERS and the
feedback outputs OT#889..896. It drives the rest of the controller only through
what MotoPlus offers MotoROS: IO reads and writes, servo on/off, alarm reset, error
cancel, job start, and the incremental-move call (:meth:`MotoRos.inc_move_tick`).

Commands that wait are generators run by :class:`~pymotoros.controller.processes.Scheduler`.
Where the real code has an outright bug we do the safe thing (see
``docs/fidelity.md``); quirks clients may rely on are kept.
"""

from __future__ import annotations

import enum
import logging
from collections.abc import Callable, Generator, Sequence
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.api import Outcome, PointData
from pymotoros.controller.cell import CellConfig
from pymotoros.controller.inform import JobRunner
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.machine import Event, OperatorMachine, OperatorState, ServoPower
from pymotoros.controller.processes import ControllerClock, Process
from pymotoros.controller.servo import ServoGroup
from pymotoros.motion import (
    GroupAxes,
    GroupInterpolator,
    Refusal,
    TrajPoint,
    check_speed,
    check_start,
    check_time,
    inc_move,
)
from pymotoros.protocol.constants import (
    MAX_DH_LINKS,
    MAX_GROUPS,
    REQUIRED_POINT_FIELDS,
    InvalidSubcode,
    MotionCommand,
    NotReadySubcode,
    ResultCode,
)

logger = logging.getLogger(__name__)

STATUS_PERIOD_MS: Final = 10
"""The status monitor reads the signals every 10 ms (§2.1 step 6, §5.1)."""
POLL_MS: Final = 50
"""MotoROS checks a condition it waits for every 50 ms (§5.1) …"""
POLL_LIMIT_MS: Final = 5000
"""… for up to 5 s."""
STOP_WAIT_MS: Final = 20
"""StopMotion waits up to 20 × 1 ms for the interpolators to go idle (§3.6)."""
ECO_REENABLE_SLEEP_MS: Final = 100
"""The sequence-0 eco-mode re-enable sleeps 100 ms after each step (§3.4 step 5.1)."""
INIT_ROS: Final = "INIT_ROS"
SKILL_START: Final = "ROS-START"
SKILL_STOP: Final = "ROS-STOP"
REQUIRED_FIELDS: Final = int(REQUIRED_POINT_FIELDS)
"""time | position | velocity (7), as a plain int (IntFlag arithmetic is slow)."""
QUEUE_COUNT_FAILURE: Final = -1
"""CHECK_QUEUE_CNT's subcode for an invalid group (§3.1)."""

DhTable = tuple[tuple[tuple[float, float, float, float], ...], ...]
Waiting = Generator[int, None, bool]
"""A wait inside a process: yields sleep times, returns whether the condition came true."""


class IncMoveReturn(enum.Enum):
    """What the controller's incremental-move call returns (names as in MotoPlus)."""

    OK = "ok"
    IMOV_UNREADY = "E_EXRCS_IMOV_UNREADY: the controller cannot take increments now"
    PFL_FUNC_BUSY = "PFL_FUNC_BUSY (-19): a PFL function is active"
    UNDER_ENERGY_SAVING = "UNDER_ENERGY_SAVING (-20): eco mode"


def _outcome(
    result: ResultCode,
    subcode: int = 0,
    detail: str = "",
    *,
    group_no: int | None = None,
    close_connection: bool = False,
) -> Outcome:
    return Outcome(
        result, subcode, group_no=group_no, close_connection=close_connection, detail=detail
    )


SUCCESS: Final = Outcome(ResultCode.SUCCESS)
FAILURE: Final = Outcome(ResultCode.FAILURE)


class MotoRos:
    """The MotoROS application's state and behaviour on one controller."""

    def __init__(
        self,
        cell: CellConfig,
        clock: ControllerClock,
        io: IoImage,
        machine: OperatorMachine,
        runner: JobRunner,
        axes: Sequence[GroupAxes],
        interpolators: Sequence[GroupInterpolator],
        servos: Sequence[ServoGroup],
    ) -> None:
        self._cell = cell
        self._clock = clock
        self._io = io
        self._machine = machine
        self._runner = runner
        self.axes = tuple(axes)
        self.interpolators = tuple(interpolators)
        self.servos = tuple(servos)
        self._num_groups = len(self.axes)
        self._dx100 = cell.controller.skillsnd
        self._sets_jog_tool = cell.controller.sets_jog_tool
        self.pfl_option = cell.pfl
        """The PFL option flag read at start-up (GP_isPflEnabled)."""
        self.jog_tool = [0] * self._num_groups
        self._busy_replies = tuple(
            _outcome(
                ResultCode.BUSY,
                detail=f"group {g}: the previous point is still being interpolated; send it again",
            )
            for g in range(self._num_groups)
        )
        """The pendant's jog tool per group (SELECT_TOOL sets it, except on FS100)."""

        # MotoROS flags (Controller.h)
        self.motion_ready = False
        self.job_ready = False
        """Set on a rising edge of OT#889, cleared on its falling edge."""
        self.stop_flag = False
        self.pfl_during_move = False
        self.inc_move_error = False
        self.inc_move_error_reason = ""
        self.skill_flags = [False, False]
        """DX100 SKILLSND "ROS-START" flags for slave 1 and slave 2 (§4.3)."""
        self.error_code = 0
        """ROBOT_STATUS error_code: the first active alarm's number (§2.6)."""
        self.last_motion_ms = 0
        """Controller time of the last increment the servos took (for the eco idle timer)."""

        # the status monitor's last reading (§2.6)
        self._alarm_bits: tuple[int, ...] = (0, 0, 0, 0)
        self._error = 0
        self._play = 0
        self._teach = 0
        self._remote = 0
        self._operating = 0
        self._hold = 0
        self._servo = 0
        self._estop_ok: tuple[int, ...] = (1, 1, 1)
        self._ros_ready = 0
        self._eco = 0
        self._pfl: tuple[int, ...] = (0, 0, 0, 0, 0)
        self.next_monitor_ms = 0
        """Controller time of the status monitor's next run."""

        self._takes_state: OperatorState | None = None
        self._takes_gen = -1
        self._takes_changes = -1
        self._takes: IncMoveReturn = IncMoveReturn.IMOV_UNREADY
        # FSU speed limit (cell option) and MotoROS's compensation for it (§5.6 step 3)
        pct = cell.servo.fsu_speed_limit_pct
        self._fsu_limit: tuple[tuple[int, ...], ...] | None = (
            None
            if pct is None
            else tuple(
                tuple(max(1, m * pct // 100) if m else 0 for m in a.max_increment)
                for a in self.axes
            )
        )
        self._to_process: list[list[int]] = [[0] * 8 for _ in self.axes]
        self._processed: list[list[int]] = [[0] * 8 for _ in self.axes]
        # IncMove retry while the controller leaves eco mode (§5.6 step 6.2)
        self._eco_retry: tuple[tuple[tuple[int, ...], ...], int, int] | None = None

    # ================================================================== start-up (§2.1)

    def boot(self) -> None:
        """Ros_Controller_Init: clear the feedback outputs, read the status, INIT_DONE."""
        io = self._io
        for address in (*signals.FEEDBACK_OUTPUTS, *signals.RESERVED_OUTPUTS):
            io.set(address, 0)
        self.status_update()
        io.set(signals.INIT_DONE, 1)
        io.set(signals.CONNECT_SERVER_RUNNING, 1)

    # ================================================================== status monitor

    def monitor_tick(self, now_ms: int) -> None:
        """Run the 10 ms status monitor when its period boundary has passed."""
        if now_ms < self.next_monitor_ms:
            return
        while self.next_monitor_ms <= now_ms:
            self.next_monitor_ms += STATUS_PERIOD_MS
        if self._io.monitor_dirty:
            self.status_update()

    def status_update(self) -> None:
        """Ros_Controller_StatusUpdate: one read of every monitored signal, then the edges."""
        io = self._io
        io.monitor_dirty = False
        get = io.get
        alarm_bits = tuple(get(a) for a in signals.ALARM_BITS)
        error = get(signals.ERROR)
        play = get(signals.PLAY)
        teach = get(signals.TEACH)
        remote = get(signals.REMOTE)
        operating = get(signals.OPERATING)
        hold = get(signals.HOLD)
        servo = get(signals.SERVO_ON)
        estop_ok = tuple(get(a) for a in signals.ESTOP_BITS)
        ros_ready = get(signals.ROS_READY)
        eco = get(signals.ECO_MODE)
        pfl = (
            tuple(get(a) for a in signals.PFL_BITS)
            if self._cell.controller.pfl_signals
            else (0, 0, 0, 0, 0)
        )

        cleared: list[str] = []
        # alarm edge: refresh error_code; clear when at least one alarm is on
        if alarm_bits != self._alarm_bits:
            if any(alarm_bits):
                alarms = self._machine.state.alarms
                self.error_code = alarms[0].code if alarms else 0
                cleared.append("alarm")
            else:
                self.error_code = 0
        # mode, job or servo loss
        if (play, teach, remote, operating, servo) != (
            self._play,
            self._teach,
            self._remote,
            self._operating,
            self._servo,
        ) and (remote != 1 or play != 1 or operating == 0 or servo == 0):
            cleared.append("mode/remote/operating/servo change")
        # OT#889: rising edge sets job-ready, falling edge clears it and the queues
        if ros_ready != self._ros_ready:
            if ros_ready:
                self.job_ready = True
            else:
                self.job_ready = False
                cleared.append("OT#889 fell")
        # PFL: a signal changes while the job is ready and PFL is active
        if self.pfl_option and pfl != self._pfl and self.job_ready and _pfl_signals_active(pfl):
            self.pfl_during_move = True
            cleared.append("PFL event")

        (
            self._alarm_bits,
            self._error,
            self._play,
            self._teach,
            self._remote,
            self._operating,
            self._hold,
            self._servo,
            self._estop_ok,
            self._ros_ready,
            self._eco,
            self._pfl,
        ) = (
            alarm_bits,
            error,
            play,
            teach,
            remote,
            operating,
            hold,
            servo,
            estop_ok,
            ros_ready,
            eco,
            pfl,
        )
        if cleared:
            if self.has_queued_motion() or any(i.pending for i in self.interpolators):
                logger.info("queues cleared by the status monitor: %s", ", ".join(cleared))
            self.clear_queues()
        self._refresh_ready()

    def _refresh_ready(self) -> None:
        ready = (
            self.job_ready
            and self._operating == 1
            and self._remote == 1
            and not self.pfl_active
            and not self.inc_move_error
            and not self.stop_flag
        )
        if ready and self._dx100:
            ready = self.skill_flags[0] and (self._num_groups < 2 or self.skill_flags[1])
        if ready != self.motion_ready:
            logger.debug("motion ready: %s", ready)
        self.motion_ready = ready

    @property
    def pfl_active(self) -> bool:
        """§4.1: only with the PFL option on YRC1000 / YRC1000micro builds."""
        if not self.pfl_option:
            return False
        return self.pfl_during_move or _pfl_signals_active(self._pfl)

    @property
    def estopped(self) -> bool:
        return not all(self._estop_ok)

    @property
    def in_error(self) -> bool:
        return any(self._alarm_bits)

    @property
    def servo_reading(self) -> tuple[bool, bool]:
        """(50073, 50727) as the status monitor last read them."""
        return bool(self._servo), bool(self._eco)

    @property
    def play_reading(self) -> bool:
        return bool(self._play)

    def not_ready_subcode(self) -> NotReadySubcode:
        """§4.2: the first matching test wins, in this order."""
        if any(self._alarm_bits):
            return NotReadySubcode.ALARM
        if self._error:
            return NotReadySubcode.ERROR
        if self.estopped:
            return NotReadySubcode.ESTOP
        if not self._play:
            return NotReadySubcode.NOT_PLAY
        if not self._remote:
            return NotReadySubcode.NOT_REMOTE
        if not self._servo or self._eco:
            return NotReadySubcode.SERVO_OFF
        if self._hold:
            return NotReadySubcode.HOLD
        if self.pfl_active:
            return NotReadySubcode.PFL_ACTIVE
        if self.inc_move_error:
            return NotReadySubcode.INC_MOVE_ERROR
        if not self._operating:
            return NotReadySubcode.NOT_STARTED
        if not self._ros_ready:
            return NotReadySubcode.WAITING_ROS
        if not self.motion_ready:
            return NotReadySubcode.SKILLSEND
        return NotReadySubcode.UNSPECIFIED

    def _not_ready(
        self, result: ResultCode = ResultCode.NOT_READY, group_no: int | None = None
    ) -> Outcome:
        sub = self.not_ready_subcode()
        detail = f"not ready for motion: {int(sub)} {sub.name}: {sub.meaning}"
        why = self._not_ready_why(sub)
        if why:
            detail += f" ({why})"
        return _outcome(result, int(sub), detail, group_no=group_no)

    def _not_ready_why(self, sub: NotReadySubcode) -> str:
        """The specifics behind a NOT_READY subcode, and what clears it."""
        s = self._machine.state
        if sub is NotReadySubcode.ALARM:
            alarms = ", ".join(f"{a.code}/{a.subcode} {a.text}".strip() for a in s.alarms)
            return f"{alarms or 'alarm output on'}; RESET_ALARM or START_TRAJ_MODE resets it"
        if sub is NotReadySubcode.ERROR:
            errors = ", ".join(f"{e.code} {e.text}".strip() for e in s.errors)
            return f"{errors or 'error output on'}; RESET_ALARM cancels it"
        if sub is NotReadySubcode.ESTOP:
            chains = ", ".join(e.name.lower() for e in sorted(s.estop, key=lambda e: e.value))
            return f"{chains or 'an'} E-stop pressed; release it, then START_TRAJ_MODE"
        if sub is NotReadySubcode.NOT_PLAY:
            return "select PLAY on the pendant, then START_TRAJ_MODE"
        if sub is NotReadySubcode.NOT_REMOTE:
            return "switch the controller to REMOTE"
        if sub is NotReadySubcode.SERVO_OFF:
            return "eco mode" if self._eco else "START_TRAJ_MODE switches servo power on"
        if sub is NotReadySubcode.HOLD:
            return "release HOLD, then START_TRAJ_MODE restarts INIT_ROS"
        if sub is NotReadySubcode.PFL_ACTIVE:
            active = [
                name
                for name, on in zip(
                    ("PFL stop", "PFL escape", "avoiding", "avoid joint", "avoid translation"),
                    self._pfl,
                    strict=True,
                )
                if on
            ]
            now = ", ".join(active) if active else "PFL signals clear, the event is latched"
            return f"{now}; START_TRAJ_MODE clears the latch"
        if sub is NotReadySubcode.INC_MOVE_ERROR:
            return f"{self.inc_move_error_reason}; START_TRAJ_MODE clears it"
        if sub is NotReadySubcode.NOT_STARTED:
            return "INIT_ROS is not running; START_TRAJ_MODE starts it"
        if sub is NotReadySubcode.WAITING_ROS:
            where = ", ".join(f"{job} line {line}" for job, line in self._runner.position())
            return f"INIT_ROS at {where or 'its start'}; OT#889 not on yet"
        if sub is NotReadySubcode.SKILLSEND:
            return self._skill_detail()
        return ""

    def _skill_detail(self) -> str:
        reasons: list[str] = []
        if self._dx100 and not self.skill_flags[0]:
            reasons.append('SKILLSND "ROS-START" not received for slave 1')
        if self._dx100 and self._num_groups > 1 and not self.skill_flags[1]:
            reasons.append('SKILLSND "ROS-START" not received for slave 2')
        if not self.job_ready:
            reasons.append("OT#889 is on but its rising edge was not seen")
        if self.stop_flag:
            reasons.append("a stop is in progress")
        return "; ".join(reasons)

    # ================================================================== queues

    def has_queued_motion(self) -> bool:
        return any(len(i.queue) for i in self.interpolators)

    def clear_queues(self) -> None:
        """Ros_MotionServer_ClearQ_All: every queue and pending point."""
        for interp in self.interpolators:
            interp.clear()

    def _stop_motion_now(self) -> bool:
        """StopMotion from the IncMove task: no waiting (the task itself is the one stopping)."""
        self.stop_flag = True
        self._refresh_ready()
        idle = not any(i.pending for i in self.interpolators)
        self.clear_queues()
        self.stop_flag = False
        self._refresh_ready()
        return idle

    def _stop_motion(self) -> Process:
        """StopMotion (§3.6): stop flag, wait ≤ 20 ms for the interpolators, clear, unflag."""
        self.stop_flag = True
        self._refresh_ready()
        start = self._clock.time_ms
        while any(i.pending for i in self.interpolators):
            if self._clock.time_ms - start >= STOP_WAIT_MS:
                break
            yield 1
        idle = not any(i.pending for i in self.interpolators)
        self.clear_queues()
        self.stop_flag = False
        self._refresh_ready()
        if idle:
            return SUCCESS
        return _outcome(
            ResultCode.FAILURE,
            detail=f"the interpolators did not go idle within {STOP_WAIT_MS} ms "
            "(the queues were cleared anyway)",
        )

    # ================================================================== MOTION_CTRL (§3.1)

    def motion_ctrl(self, group_no: int, command: int) -> Process:
        """One MOTO_MOTION_CTRL request, as a process."""
        if command == MotionCommand.CHECK_MOTION_READY:
            return SUCCESS if self.motion_ready else self._not_ready(ResultCode.FALSE)
        if command == MotionCommand.CHECK_QUEUE_CNT:
            if not 0 <= group_no < self._num_groups:
                return _outcome(
                    ResultCode.FAILURE,
                    QUEUE_COUNT_FAILURE,
                    f"CHECK_QUEUE_CNT: group {group_no} does not exist "
                    f"({self._num_groups} group(s): 0..{self._num_groups - 1})",
                )
            return _outcome(ResultCode.SUCCESS, len(self.interpolators[group_no].queue))
        if command == MotionCommand.STOP_MOTION:
            return (yield from self._stop_motion())
        if command == MotionCommand.START_SERVOS:
            return (yield from self._start_servos())
        if command == MotionCommand.STOP_SERVOS:
            return (yield from self._stop_servos())
        if command == MotionCommand.RESET_ALARM:
            return self._reset_alarm()
        if command == MotionCommand.START_TRAJ_MODE:
            return (yield from self._start_traj_mode())
        if command == MotionCommand.STOP_TRAJ_MODE:
            return (yield from self._stop_traj_mode())
        if command == MotionCommand.DISCONNECT:
            outcome = yield from self._stop_traj_mode()
            if outcome.ok:
                return _outcome(ResultCode.SUCCESS, close_connection=True)
            return outcome
        known = ", ".join(f"{c.name} {int(c)}" for c in MotionCommand)
        return _outcome(
            ResultCode.INVALID,
            InvalidSubcode.COMMAND,
            f"unknown MOTO_MOTION_CTRL command {command} (known: {known}); MotoROS 1.9.12 "
            "would resend its previous reply, we answer 3006 INVALID_COMMAND",
        )

    def _wait_until(self, condition: Callable[[], bool]) -> Waiting:
        """Check ``condition`` every 50 ms for up to 5 s; True if it came true."""
        start = self._clock.time_ms
        while not condition():
            if self._clock.time_ms - start >= POLL_LIMIT_MS:
                return False
            yield POLL_MS
        return True

    def _servo_is_on(self) -> bool:
        s = self._machine.state
        return s.servo_on and not s.eco

    def _servo_is_off(self) -> bool:
        return self._machine.state.servo is ServoPower.OFF

    def _leave_eco(self) -> Waiting:
        """Disable eco mode: servo OFF, then wait ≤ 5 s for 50727 to drop."""
        self._machine.fire(Event.SERVO_OFF, self._clock.time_ms)
        return (yield from self._wait_until(lambda: not self._machine.state.eco))

    def _start_servos(self) -> Process:
        if self._machine.state.eco:
            yield from self._leave_eco()
        refused = self._machine.fire(Event.REQUEST_SERVO_ON, self._clock.time_ms)
        if (yield from self._wait_until(self._servo_is_on)):
            return SUCCESS
        return _outcome(
            ResultCode.FAILURE,
            detail=f"servo power did not come on within {POLL_LIMIT_MS} ms"
            + (f" (servo on refused: {refused})" if refused else ""),
        )

    def _stop_servos(self) -> Process:
        stopped = yield from self._stop_motion()
        self._machine.fire(Event.SERVO_OFF, self._clock.time_ms)
        off = yield from self._wait_until(self._servo_is_off)
        if stopped.ok and off:
            return SUCCESS
        return _outcome(ResultCode.FAILURE, detail=stopped.detail or "servo power stayed on")

    def _reset_alarm(self) -> Outcome:
        s = self._machine.state
        now = self._clock.time_ms
        if s.alarms:
            self._machine.fire(Event.RESET_ALARMS, now)
        if s.errors:
            self._machine.fire(Event.CANCEL_ERRORS, now)
        return SUCCESS

    def _start_traj_mode(self) -> Process:
        """§3.2, step by step."""
        machine = self._machine
        # 1. status update; clear the PFL and inc-move-error latches
        self.status_update()
        self.pfl_during_move = False
        self.inc_move_error = False
        self._refresh_ready()
        # 2. already ready
        if self.motion_ready:
            return SUCCESS
        ok = self._prepare_for_job()
        if ok:
            ok = yield from self._power_up()
        if ok:
            # 8. clear leftover data; every group restarts from its commanded position
            if self.has_queued_motion():
                self.clear_queues()
            # 9. start INIT_ROS, then wait for motion-ready
            refused = machine.fire(Event.START_JOB, self._clock.time_ms)
            if refused is None:
                yield from self._wait_until(lambda: self.motion_ready)
            else:
                logger.info("START_TRAJ_MODE: cannot start %s: %s", INIT_ROS, refused)
        # 10. final check
        return self._final_check()

    def _final_check(self) -> Outcome:
        self.status_update()
        if self.motion_ready:
            return SUCCESS
        return self._not_ready()

    def _prepare_for_job(self) -> bool:
        """Steps 3–6: refuse what needs an operator, cancel errors, reset alarms."""
        s = self._machine.state
        now = self._clock.time_ms
        if self._operating:
            logger.info("START_TRAJ_MODE: another job is running; MotoROS does not interrupt it")
            return False
        if self.estopped or self._hold or not self._remote:
            return False
        if self._error:
            self._machine.fire(Event.CANCEL_ERRORS, now)
        if any(self._alarm_bits) or s.alarms:
            self._machine.fire(Event.RESET_ALARMS, now)
            self.status_update()
            if any(self._alarm_bits):
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
        return (yield from self._wait_until(self._servo_is_on))

    def _stop_traj_mode(self) -> Process:
        """§3.3: queues must be empty; StopMotion; OT#890 ON releases the job."""
        if self.has_queued_motion():
            counts = ", ".join(
                f"{a.name}: {len(i.queue)}"
                for a, i in zip(self.axes, self.interpolators, strict=True)
            )
            return _outcome(
                ResultCode.FAILURE,
                detail=f"increments are still queued ({counts}); wait for the motion to end "
                "or send STOP_MOTION first",
            )
        stopped = yield from self._stop_motion()
        if not stopped.ok:
            return stopped
        self._io.set(signals.ROS_DONE, 1)
        return SUCCESS

    # ================================================================== trajectory points

    def _to_traj(self, point: PointData) -> TrajPoint:
        return TrajPoint(point.time, tuple(point.pos[:8]), tuple(point.vel[:8]))

    def _refused(self, refusal: Refusal, point_desc: str, group_no: int | None = None) -> Outcome:
        return _outcome(
            ResultCode.INVALID,
            int(refusal.subcode),
            f"{point_desc}: {refusal.message}",
            group_no=group_no,
        )

    def trajectory_point(self, sequence: int, point: PointData) -> Process:
        """JOINT_TRAJ_PT_FULL (14): §3.4, in its order."""
        if not self.motion_ready:
            return self._not_ready()
        g = point.group_no
        if not 0 <= g < self._num_groups:
            return self._bad_group(g)
        if point.valid_fields & REQUIRED_FIELDS != REQUIRED_FIELDS:
            return self._insufficient(point)
        traj = self._to_traj(point)
        refusal = check_time(traj)
        if refusal is not None:
            return self._refused(refusal, f"point {sequence} of group {g}")
        if sequence == 0:
            if self._machine.state.eco:
                yield from self._eco_reenable()
            return self._start_group(g, traj, sequence)
        if sequence > 0:
            return self._queue_point(g, traj, sequence)
        return self._bad_sequence(sequence)

    def trajectory_point_ex(self, sequence: int, points: Sequence[PointData]) -> Process:
        """MOTO_JOINT_TRAJ_PT_FULL_EX (2016): §3.5, in its order."""
        if not points:
            return _outcome(
                ResultCode.INVALID,
                InvalidSubcode.DATA,
                "JOINT_TRAJ_PT_FULL_EX with no group; MotoROS 1.9.12 would resend its "
                "previous reply, we answer 3010 INVALID_DATA",
                group_no=-1,
            )
        if not self.motion_ready:
            return self._not_ready(group_no=points[-1].group_no)
        for p in points:
            g = p.group_no
            if not 0 <= g < self._num_groups:
                return self._bad_group(g, group_no=g)
            if self.interpolators[g].pending:
                return self._busy(g, sequence, group_no=g)
            if p.valid_fields & REQUIRED_FIELDS != REQUIRED_FIELDS:
                return self._insufficient(p, group_no=g)
        last = points[-1].group_no
        for p in points:
            g = p.group_no
            traj = self._to_traj(p)
            if sequence == 0:
                if self._machine.state.eco:
                    yield from self._eco_reenable()
                outcome = self._start_group(g, traj, sequence, group_no=g)
            elif sequence > 0:
                outcome = self._queue_point(g, traj, sequence, group_no=g)
            else:
                return self._bad_sequence(sequence, group_no=g)
            if not outcome.ok:
                return outcome
        return _outcome(ResultCode.SUCCESS, group_no=last)

    def _bad_group(self, g: int, group_no: int | None = None) -> Outcome:
        return _outcome(
            ResultCode.INVALID,
            InvalidSubcode.GROUPNO,
            f"group {g} does not exist ({self._num_groups} group(s): 0..{self._num_groups - 1})",
            group_no=group_no,
        )

    def _insufficient(self, point: PointData, group_no: int | None = None) -> Outcome:
        return _outcome(
            ResultCode.INVALID,
            InvalidSubcode.DATA_INSUFFICIENT,
            f"group {point.group_no}: valid_fields {point.valid_fields} lacks "
            "time (1), position (2) or velocity (4); MotoROS needs all three",
            group_no=group_no,
        )

    def _bad_sequence(self, sequence: int, group_no: int | None = None) -> Outcome:
        return _outcome(
            ResultCode.INVALID,
            InvalidSubcode.SEQUENCE,
            f"sequence {sequence} is negative; a trajectory starts at 0",
            group_no=group_no,
        )

    def _busy(self, g: int, sequence: int, group_no: int | None = None) -> Outcome:
        if group_no is None:
            return self._busy_replies[g]
        return _outcome(ResultCode.BUSY, detail=self._busy_replies[g].detail, group_no=group_no)

    def _start_group(
        self, g: int, traj: TrajPoint, sequence: int, group_no: int | None = None
    ) -> Outcome:
        """Sequence 0: initialise the group, then the interleaved start/speed checks."""
        interp = self.interpolators[g]
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
        commanded = tuple(self.servos[g].command)
        interp.start(traj, commanded)
        refusal = check_start(traj, commanded, self.axes[g])
        if refusal is not None:
            return self._refused(refusal, f"point 0 of group {g}", group_no=group_no)
        return _outcome(ResultCode.SUCCESS, group_no=group_no)

    def _queue_point(
        self, g: int, traj: TrajPoint, sequence: int, group_no: int | None = None
    ) -> Outcome:
        interp = self.interpolators[g]
        if interp.pending:
            return self._busy(g, sequence, group_no=group_no)
        refusal = check_speed(traj, self.axes[g])
        if refusal is not None:
            return self._refused(refusal, f"point {sequence} of group {g}", group_no=group_no)
        interp.set_pending(traj)
        return _outcome(ResultCode.SUCCESS, group_no=group_no)

    def _eco_reenable(self) -> Process:
        """v1.9.12: sequence 0 in eco mode runs STOP_TRAJ_MODE and START_TRAJ_MODE."""
        logger.info("trajectory start in eco mode: leaving and re-entering trajectory mode")
        yield from self._stop_traj_mode()
        yield ECO_REENABLE_SLEEP_MS
        yield from self._start_traj_mode()
        yield ECO_REENABLE_SLEEP_MS
        return SUCCESS

    # ================================================================== tools and DH

    def select_tool(self, group_no: int, tool: int) -> Outcome:
        """SELECT_TOOL (§5.8)."""
        if not 0 <= group_no < self._num_groups:
            return self._bad_group(group_no)
        if not 0 <= tool <= 63:
            return _outcome(
                ResultCode.INVALID,
                InvalidSubcode.DATA_TOOLNO,
                f"tool {tool} is outside 0..63",
            )
        self.interpolators[group_no].tool = tool
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

    # ================================================================== the tasks, per tick

    def fill_tick(self) -> None:
        """Every AddToIncQueue task's turn."""
        ready = self.motion_ready
        for interp in self.interpolators:
            interp.fill(ready)

    def inc_move_tick(self) -> bool:
        """The IncMove task's turn; True if increments reached the servos this tick."""
        if self._eco_retry is not None:
            return self._retry_eco()
        if not self.motion_ready or self.stop_flag:
            if self._fsu_limit is not None:
                self._fsu_reset()
            return False
        if self._fsu_limit is not None:
            return self._inc_move_fsu(self._fsu_limit)
        incs = inc_move(self.interpolators)
        if incs is None:
            return False
        result = self._controller_takes_increments()
        if result is IncMoveReturn.OK:
            self.last_motion_ms = self._clock.time_ms
            servos = self.servos
            if len(servos) == 1:
                servos[0].apply(incs[0].pulses)
            else:
                for servo, inc in zip(servos, incs, strict=True):
                    servo.apply(inc.pulses)
            return True
        return self._inc_move_failed(result, tuple(i.pulses for i in incs))

    @property
    def unprocessed_pulses(self) -> tuple[tuple[int, ...], ...]:
        """Per group, pulses sent (or due) that the controller has not executed (FSU)."""
        return tuple(
            tuple(a - b for a, b in zip(t, p, strict=True))
            for t, p in zip(self._to_process, self._processed, strict=True)
        )

    def _fsu_reset(self) -> None:
        for g in range(self._num_groups):
            self._to_process[g] = [0] * 8
            self._processed[g] = [0] * 8

    def _inc_move_fsu(self, limits: tuple[tuple[int, ...], ...]) -> bool:
        """IncMove with the v1.9.12 FSU compensation, on a controller whose FSU clips.

        The controller executes at most ``limits`` pulses per axis and tick and drops
        the rest. MotoROS measures what was executed (the change of the commanded
        position), keeps the unexecuted pulses, resends them clamped to what the
        controller took last time (or the axis maximum if it took nothing), and does
        not read its queue while such pulses remain.
        """
        missing = False
        remaining: list[list[int]] = []
        for g in range(self._num_groups):
            rest = [a - b for a, b in zip(self._to_process[g], self._processed[g], strict=True)]
            remaining.append(rest)
            missing = missing or any(rest)
        if missing:
            sends = []
            for g, rest in enumerate(remaining):
                taken = self._processed[g]
                max_inc = self.axes[g].max_increment
                clamp = [abs(t) or m for t, m in zip(taken, max_inc, strict=True)]
                sends.append(tuple(max(-c, min(c, r)) for r, c in zip(rest, clamp, strict=True)))
            to_process = remaining
        else:
            incs = inc_move(self.interpolators)
            if incs is None:
                self._fsu_reset()
                return False
            sends = [i.pulses for i in incs]
            to_process = [list(p) for p in sends]
        result = self._controller_takes_increments()
        if result is not IncMoveReturn.OK:
            self._fsu_reset()
            return self._inc_move_failed(result, tuple(tuple(s) for s in sends))
        self.last_motion_ms = self._clock.time_ms
        for g, servo in enumerate(self.servos):
            executed = servo.apply_limited(sends[g], limits[g])
            self._processed[g] = list(executed)
            self._to_process[g] = to_process[g]
        return True

    def _controller_takes_increments(self) -> IncMoveReturn:
        """The controller's answer to mpExRcsIncrementMove (cached while nothing changes)."""
        s = self._machine.state
        gen = self._runner.generation
        changes = self._io.monitored_changes
        if s is self._takes_state and gen == self._takes_gen and changes == self._takes_changes:
            return self._takes
        self._takes_state, self._takes_gen, self._takes_changes = s, gen, changes
        self._takes = self._controller_answer(s)
        return self._takes

    def _controller_answer(self, s: OperatorState) -> IncMoveReturn:
        if s.eco and s.servo_on:
            return IncMoveReturn.UNDER_ENERGY_SAVING
        if self.pfl_option and (self._io.get(signals.PFL_STOP) or self._io.get(signals.PFL_ESCAPE)):
            return IncMoveReturn.PFL_FUNC_BUSY
        if (
            s.servo is not ServoPower.ON
            or not s.job_running
            or s.hold
            or s.estop
            or s.alarms
            or not self._runner.at_wait
        ):
            return IncMoveReturn.IMOV_UNREADY
        return IncMoveReturn.OK

    def _inc_move_failed(self, result: IncMoveReturn, pulses: tuple[tuple[int, ...], ...]) -> bool:
        """§5.6 step 6."""
        self.status_update()
        s = self._machine.state
        if result is IncMoveReturn.PFL_FUNC_BUSY or (
            result is IncMoveReturn.IMOV_UNREADY
            and self.pfl_option
            and not (s.estop or s.hold or s.alarms or s.errors)
        ):
            self.pfl_during_move = True
        if result is IncMoveReturn.UNDER_ENERGY_SAVING:
            now = self._clock.time_ms
            self._machine.fire(Event.WAKE_FROM_ECO, now)
            self._eco_retry = (pulses, now + POLL_LIMIT_MS, now + POLL_MS)
            return False
        logger.warning(
            "incremental move refused (%s); motion is refused with 5012 INC_MOVE_ERROR "
            "until the next START_TRAJ_MODE",
            result.value,
        )
        self.inc_move_error = True
        self.inc_move_error_reason = f"an incremental move was refused: {result.value}"
        self._stop_motion_now()
        return False

    def _retry_eco(self) -> bool:
        if self._eco_retry is None:
            return False
        pulses, deadline, next_try = self._eco_retry
        now = self._clock.time_ms
        if now < next_try:
            return False
        result = self._controller_takes_increments()
        if result is IncMoveReturn.OK:
            self._eco_retry = None
            self.last_motion_ms = now
            for servo, p in zip(self.servos, pulses, strict=True):
                servo.apply(p)
            return True
        if result is IncMoveReturn.UNDER_ENERGY_SAVING and now < deadline:
            self._eco_retry = (pulses, deadline, next_try + POLL_MS)
            return False
        self._eco_retry = None
        return self._inc_move_failed(
            IncMoveReturn.IMOV_UNREADY if result is IncMoveReturn.UNDER_ENERGY_SAVING else result,
            pulses,
        )

    # ================================================================== jobs, connections

    def on_skill(self, slave: int, text: str) -> None:
        """A SKILLSND reached slave ``slave`` (DX100 listener tasks, §4.3)."""
        if not self._dx100 or slave not in (1, 2) or (slave == 2 and self._num_groups < 2):
            logger.debug('SKILLSND SL%d "%s": no MotoROS listener for it', slave, text)
            return
        if text == SKILL_START:
            self.skill_flags[slave - 1] = True
        elif text == SKILL_STOP:
            self.skill_flags[slave - 1] = False
        else:
            logger.info('SKILLSND SL%d "%s" (ignored by MotoROS)', slave, text)
        self._refresh_ready()

    def on_job_stopped(self) -> None:
        """The job ended or was stopped: the skill commands end with it."""
        if any(self.skill_flags):
            self.skill_flags = [False, False]
            self._refresh_ready()

    def motion_connected(self) -> None:
        self._io.set(signals.MOTION_SERVER_CONNECTED, 1)

    def motion_disconnected(self) -> None:
        self._io.set(signals.MOTION_SERVER_CONNECTED, 0)
        if self.has_queued_motion():
            logger.info(
                "motion connection closed with increments queued: clearing them "
                "(MotoROS 1.9.12 would keep them and resume on the next connection)"
            )
        self.clear_queues()

    def state_clients_changed(self, count: int) -> None:
        self._io.set(signals.STATE_SERVER_CONNECTED, count > 0)

    def io_connected(self) -> None:
        self._io.set(signals.IO_SERVER_CONNECTED, 1)

    @property
    def waiting(self) -> bool:
        """IncMove is retrying while the controller leaves eco mode."""
        return self._eco_retry is not None


def _pfl_signals_active(pfl: tuple[int, ...]) -> bool:
    stop, escape, avoiding, avoid_joint, avoid_translation = pfl
    return bool(stop or escape or (avoiding and (avoid_joint or avoid_translation)))
