"""The status monitor and the motion-ready flag (reference §2.6, §3.6, §4).

:class:`Readiness` is MotoROS's view of the controller: the 10 ms status monitor
(Ros_Controller_StatusUpdate) and its queue-clearing edges, the flags of
``Controller.h`` (motion-ready, job-ready, stop, PFL and inc-move-error latches, the
DX100 skill flags) and the NOT_READY subcode order with the specifics behind it.
Everything that needs to know whether motion is possible asks it.
"""

from __future__ import annotations

import logging
from typing import Final

from pymotoros.controller import signals
from pymotoros.controller.api import Outcome
from pymotoros.controller.cell import CellConfig
from pymotoros.controller.inform import JobRunner
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.machine import OperatorMachine
from pymotoros.controller.queues import MotionQueues
from pymotoros.controller.replies import reply
from pymotoros.protocol.constants import NotReadySubcode, ResultCode

logger = logging.getLogger(__name__)

STATUS_PERIOD_MS: Final = 10
"""The status monitor reads the signals every 10 ms (§2.1 step 6, §5.1)."""


class Readiness:
    """The status monitor's last reading, MotoROS's flags, and whether motion is possible."""

    def __init__(
        self,
        cell: CellConfig,
        io: IoImage,
        machine: OperatorMachine,
        runner: JobRunner,
        queues: MotionQueues,
        num_groups: int,
    ) -> None:
        self._io = io
        self._machine = machine
        self._runner = runner
        self._queues = queues
        self._num_groups = num_groups
        self._dx100 = cell.controller.skillsnd
        self._pfl_signals = cell.controller.pfl_signals
        self.pfl_option = cell.pfl
        """The PFL option flag read at start-up (GP_isPflEnabled)."""

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

        # the status monitor's last reading (§2.6)
        self.alarm_bits: tuple[int, ...] = (0, 0, 0, 0)
        self.error = 0
        self.play = 0
        self.teach = 0
        self.remote = 0
        self.operating = 0
        self.hold = 0
        self.servo = 0
        self.estop_ok: tuple[int, ...] = (1, 1, 1)
        self.ros_ready = 0
        self.eco = 0
        self.pfl: tuple[int, ...] = (0, 0, 0, 0, 0)
        self.next_monitor_ms = 0
        """Controller time of the status monitor's next run."""

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
        pfl = tuple(get(a) for a in signals.PFL_BITS) if self._pfl_signals else (0, 0, 0, 0, 0)

        cleared: list[str] = []
        # alarm edge: refresh error_code; clear when at least one alarm is on
        if alarm_bits != self.alarm_bits:
            if any(alarm_bits):
                alarms = self._machine.state.alarms
                self.error_code = alarms[0].code if alarms else 0
                cleared.append("alarm")
            else:
                self.error_code = 0
        # mode, job or servo loss
        if (play, teach, remote, operating, servo) != (
            self.play,
            self.teach,
            self.remote,
            self.operating,
            self.servo,
        ) and (remote != 1 or play != 1 or operating == 0 or servo == 0):
            cleared.append("mode/remote/operating/servo change")
        # OT#889: rising edge sets job-ready, falling edge clears it and the queues
        if ros_ready != self.ros_ready:
            if ros_ready:
                self.job_ready = True
            else:
                self.job_ready = False
                cleared.append("OT#889 fell")
        # PFL: a signal changes while the job is ready and PFL is active
        if self.pfl_option and pfl != self.pfl and self.job_ready and pfl_signals_active(pfl):
            self.pfl_during_move = True
            cleared.append("PFL event")

        (
            self.alarm_bits,
            self.error,
            self.play,
            self.teach,
            self.remote,
            self.operating,
            self.hold,
            self.servo,
            self.estop_ok,
            self.ros_ready,
            self.eco,
            self.pfl,
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
            queues = self._queues
            if queues.has_queued_motion() or queues.any_pending():
                logger.info("queues cleared by the status monitor: %s", ", ".join(cleared))
            queues.clear()
        self.refresh_ready()

    def refresh_ready(self) -> None:
        ready = (
            self.job_ready
            and self.operating == 1
            and self.remote == 1
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
        return self.pfl_during_move or pfl_signals_active(self.pfl)

    @property
    def estopped(self) -> bool:
        return not all(self.estop_ok)

    @property
    def in_error(self) -> bool:
        return any(self.alarm_bits)

    @property
    def servo_reading(self) -> tuple[bool, bool]:
        """(50073, 50727) as the status monitor last read them."""
        return bool(self.servo), bool(self.eco)

    @property
    def play_reading(self) -> bool:
        return bool(self.play)

    # ================================================================== NOT_READY (§4.2)

    def not_ready_subcode(self) -> NotReadySubcode:
        """§4.2: the first matching test wins, in this order."""
        if any(self.alarm_bits):
            return NotReadySubcode.ALARM
        if self.error:
            return NotReadySubcode.ERROR
        if self.estopped:
            return NotReadySubcode.ESTOP
        if not self.play:
            return NotReadySubcode.NOT_PLAY
        if not self.remote:
            return NotReadySubcode.NOT_REMOTE
        if not self.servo or self.eco:
            return NotReadySubcode.SERVO_OFF
        if self.hold:
            return NotReadySubcode.HOLD
        if self.pfl_active:
            return NotReadySubcode.PFL_ACTIVE
        if self.inc_move_error:
            return NotReadySubcode.INC_MOVE_ERROR
        if not self.operating:
            return NotReadySubcode.NOT_STARTED
        if not self.ros_ready:
            return NotReadySubcode.WAITING_ROS
        if not self.motion_ready:
            return NotReadySubcode.SKILLSEND
        return NotReadySubcode.UNSPECIFIED

    def not_ready(
        self, result: ResultCode = ResultCode.NOT_READY, group_no: int | None = None
    ) -> Outcome:
        sub = self.not_ready_subcode()
        detail = f"not ready for motion: {int(sub)} {sub.name}: {sub.meaning}"
        why = self._not_ready_why(sub)
        if why:
            detail += f" ({why})"
        return reply(result, int(sub), detail, group_no=group_no)

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
            return "eco mode" if self.eco else "START_TRAJ_MODE switches servo power on"
        if sub is NotReadySubcode.HOLD:
            return "release HOLD, then START_TRAJ_MODE restarts INIT_ROS"
        if sub is NotReadySubcode.PFL_ACTIVE:
            active = [
                name
                for name, on in zip(
                    ("PFL stop", "PFL escape", "avoiding", "avoid joint", "avoid translation"),
                    self.pfl,
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


def pfl_signals_active(pfl: tuple[int, ...]) -> bool:
    stop, escape, avoiding, avoid_joint, avoid_translation = pfl
    return bool(stop or escape or (avoiding and (avoid_joint or avoid_translation)))
