"""The status monitor and the motion-ready flag (reference §2.6, §3.6, §4).

:class:`Readiness` is MotoROS's view of the controller: the 10 ms status monitor
(Ros_Controller_StatusUpdate) and its queue-clearing edges, the flags of
``Controller.h`` (motion-ready, job-ready, stop, PFL and inc-move-error latches, the
DX100 skill flags) and the NOT_READY subcode order with the specifics behind it.
Everything that needs to know whether motion is possible asks it.
"""

from __future__ import annotations

import logging
from typing import Final, NamedTuple

from pymotoros.controller import signals
from pymotoros.controller.api import Outcome
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.replies import reply
from pymotoros.protocol.constants import NotReadySubcode, ResultCode

logger = logging.getLogger(__name__)

STATUS_PERIOD_MS: Final = 10
"""The status monitor reads the signals every 10 ms (§2.1 step 6, §5.1)."""


class StatusReading(NamedTuple):
    """One read of every signal the status monitor watches (§2.6), as 0/1 values."""

    alarm_bits: tuple[int, ...]
    """Major, minor, system, user alarm outputs (50010..50013)."""
    error: int
    play: int
    teach: int
    remote: int
    operating: int
    hold: int
    servo: int
    estop_ok: tuple[int, ...]
    """The three E-stop inputs; 1 = not pressed."""
    ros_ready: int
    """OT#889 (11120)."""
    eco: int
    pfl: tuple[int, ...]
    """PFL stop, escape, avoiding, avoid joint, avoid translation (0 without PFL signals)."""


BOOT_READING: Final = StatusReading(
    (0, 0, 0, 0), 0, 0, 0, 0, 0, 0, 0, (1, 1, 1), 0, 0, (0, 0, 0, 0, 0)
)
"""What the monitor is taken to have read before its first run."""


class Readiness:
    """The status monitor's last reading, MotoROS's flags, and whether motion is possible.

    The flags of ``Controller.h`` are read-only from outside: each change goes through
    an intention-revealing method (:meth:`latch_pfl_event`, :meth:`latch_inc_move_error`,
    :meth:`clear_latches`, :meth:`begin_stop` …) or through the status monitor, and every
    one of them ends in :meth:`_refresh`, the single place :attr:`motion_ready` is
    computed. The flag therefore always agrees with its inputs; no caller can leave it
    stale. :meth:`outlook` answers what the flag will be once the monitor has seen the
    current signals (the operator's view, between two 10 ms runs).
    """

    def __init__(self, ctx: MotoRosContext) -> None:
        cell = ctx.cell
        self._io = ctx.io
        self._machine = ctx.machine
        self._runner = ctx.runner
        self._queues = ctx.queues
        self._num_groups = ctx.num_groups
        self._dx100 = cell.controller.skillsnd
        self._pfl_signals = cell.controller.pfl_signals
        self.pfl_option: Final = cell.pfl
        """The PFL option flag read at start-up (GP_isPflEnabled)."""

        # MotoROS flags (Controller.h): change them only through the methods below
        self._motion_ready = False
        self._job_ready = False
        self._stop_flag = False
        self._pfl_during_move = False
        self._inc_move_error = False
        self._inc_move_error_reason = ""
        self._skill_flags = (False, False)
        self._error_code = 0
        self._r = BOOT_READING
        """The status monitor's last reading (§2.6)."""
        self.next_monitor_ms = 0
        """Controller time of the status monitor's next run."""

    # ================================================================== the flags, read-only

    @property
    def reading(self) -> StatusReading:
        """The status monitor's last reading (§2.6)."""
        return self._r

    @property
    def error_code(self) -> int:
        """ROBOT_STATUS error_code: the first active alarm's number (§2.6)."""
        return self._error_code

    @property
    def motion_ready(self) -> bool:
        """§4.1, as of the status monitor's last reading and the current flags."""
        return self._motion_ready

    @property
    def job_ready(self) -> bool:
        """Set on a rising edge of OT#889, cleared on its falling edge."""
        return self._job_ready

    @property
    def stop_flag(self) -> bool:
        """StopMotion is in progress (§3.6)."""
        return self._stop_flag

    @property
    def pfl_during_move(self) -> bool:
        """The "PFL during ROS move" latch behind 5011 (§4.4)."""
        return self._pfl_during_move

    @property
    def inc_move_error(self) -> bool:
        """The inc-move-error latch behind 5012 (§5.6 step 6)."""
        return self._inc_move_error

    @property
    def inc_move_error_reason(self) -> str:
        return self._inc_move_error_reason

    @property
    def skill_flags(self) -> tuple[bool, bool]:
        """DX100 SKILLSND "ROS-START" flags for slave 1 and slave 2 (§4.3)."""
        return self._skill_flags

    # ================================================================== changing them

    def latch_pfl_event(self) -> None:
        """An increment was refused for a PFL reason: 5011 until the next START_TRAJ_MODE."""
        self._pfl_during_move = True
        self._refresh()

    def latch_inc_move_error(self, reason: str) -> None:
        """An increment was refused: 5012 until the next START_TRAJ_MODE (§5.6 step 6)."""
        self._inc_move_error = True
        self._inc_move_error_reason = reason
        self._refresh()

    def clear_latches(self) -> None:
        """START_TRAJ_MODE step 1: clear the PFL and inc-move-error latches (§3.2)."""
        self._pfl_during_move = False
        self._inc_move_error = False
        self._refresh()

    def clear_pfl_latch(self) -> None:
        """Clear only the PFL latch (tests peel the NOT_READY conditions off one by one)."""
        self._pfl_during_move = False
        self._refresh()

    def clear_inc_move_error(self) -> None:
        """Clear only the inc-move-error latch (tests, as :meth:`clear_pfl_latch`)."""
        self._inc_move_error = False
        self._refresh()

    def forget_job_ready(self) -> None:
        """Lose the job-ready flag without an OT#889 edge (tests: the 5010 case of §4.2)."""
        self._job_ready = False
        self._refresh()

    def begin_stop(self) -> None:
        """StopMotion raises the stop flag: motion is not ready while it stops (§3.6)."""
        self._stop_flag = True
        self._refresh()

    def end_stop(self) -> None:
        """StopMotion is done: lower the stop flag."""
        self._stop_flag = False
        self._refresh()

    def set_skill_flag(self, slave: int, on: bool) -> None:
        """A SKILLSND "ROS-START" (on) or "ROS-STOP" (off) reached slave 1 or 2 (§4.3)."""
        flags = list(self._skill_flags)
        flags[slave - 1] = on
        self._skill_flags = (flags[0], flags[1])
        self._refresh()

    def clear_skill_flags(self) -> None:
        """The skill commands ended with the job (§4.3)."""
        self._skill_flags = (False, False)
        self._refresh()

    def _refresh(self) -> None:
        """The one place the motion-ready flag is computed (§4.1)."""
        ready = self._ready(
            self._job_ready, self._r.operating, self._r.remote, self._pfl_during_move, self._r.pfl
        )
        if ready != self._motion_ready:
            logger.debug("motion ready: %s", ready)
        self._motion_ready = ready

    def _ready(
        self,
        job_ready: bool,
        operating: int,
        remote: int,
        pfl_latched: bool,
        pfl: tuple[int, ...],
    ) -> bool:
        """§4.1 for the given reading and latches, with the current stop and skill flags."""
        ready = (
            job_ready
            and operating == 1
            and remote == 1
            and not (self.pfl_option and (pfl_latched or pfl_signals_active(pfl)))
            and not self._inc_move_error
            and not self._stop_flag
        )
        if ready and self._dx100:
            skill = self._skill_flags
            ready = skill[0] and (self._num_groups < 2 or skill[1])
        return ready

    # ================================================================== start-up (§2.1)

    def boot(self) -> None:
        """Ros_Controller_Init: clear the feedback outputs, read the status, INIT_DONE."""
        self.init_read()
        self.init_done()

    def init_read(self) -> None:
        """Ros_Controller_Init's first steps: clear the feedback outputs, read the status once."""
        io = self._io
        for address in (*signals.FEEDBACK_OUTPUTS, *signals.RESERVED_OUTPUTS):
            io.set(address, 0)
        self.status_update()

    def init_done(self) -> None:
        """The start-up checks passed: INIT_DONE on, the connection server runs (§2.1)."""
        io = self._io
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

    def _read(self) -> StatusReading:
        """One read of every monitored signal."""
        get = self._io.get
        return StatusReading(
            tuple(get(a) for a in signals.ALARM_BITS),
            get(signals.ERROR),
            get(signals.PLAY),
            get(signals.TEACH),
            get(signals.REMOTE),
            get(signals.OPERATING),
            get(signals.HOLD),
            get(signals.SERVO_ON),
            tuple(get(a) for a in signals.ESTOP_BITS),
            get(signals.ROS_READY),
            get(signals.ECO_MODE),
            tuple(get(a) for a in signals.PFL_BITS) if self._pfl_signals else (0, 0, 0, 0, 0),
        )

    def _edges(self, ros_ready: int, pfl: tuple[int, ...]) -> tuple[bool, bool]:
        """(job-ready, PFL event) from the monitor's OT#889 and PFL edges (§2.6, §4.1).

        OT#889's rising edge sets job-ready and its falling edge clears it; a PFL signal
        that changes to active while the job is ready (PFL option on) is a PFL event.
        """
        job_ready = self._job_ready
        last = self._r
        if ros_ready != last.ros_ready:
            job_ready = bool(ros_ready)
        pfl_event = self.pfl_option and pfl != last.pfl and job_ready and pfl_signals_active(pfl)
        return job_ready, pfl_event

    def outlook(self) -> bool:
        """The motion-ready flag once the monitor has seen the current signals.

        MotoROS reads its inputs every 10 ms, so :attr:`motion_ready` may lag an
        operator action by up to one monitor period. This is the same computation on
        the signals as they are now, without the monitor's side effects: what a
        CHECK_MOTION_READY will answer right after the monitor's next run.
        """
        if not self._io.monitor_dirty:
            return self._motion_ready
        r = self._read()
        job_ready, pfl_event = self._edges(r.ros_ready, r.pfl)
        latched = self._pfl_during_move or pfl_event
        return self._ready(job_ready, r.operating, r.remote, latched, r.pfl)

    def status_update(self) -> None:
        """Ros_Controller_StatusUpdate: one read of every monitored signal, then the edges."""
        io = self._io
        io.monitor_dirty = False
        r = self._read()
        last = self._r

        cleared: list[str] = []
        # alarm edge: refresh error_code; clear when at least one alarm is on
        if r.alarm_bits != last.alarm_bits:
            if any(r.alarm_bits):
                alarms = self._machine.state.alarms
                self._error_code = alarms[0].code if alarms else 0
                cleared.append("alarm")
            else:
                self._error_code = 0
        # mode, job or servo loss
        if (r.play, r.teach, r.remote, r.operating, r.servo) != (
            last.play,
            last.teach,
            last.remote,
            last.operating,
            last.servo,
        ) and (r.remote != 1 or r.play != 1 or r.operating == 0 or r.servo == 0):
            cleared.append("mode/remote/operating/servo change")
        # OT#889: rising edge sets job-ready, falling edge clears it and the queues;
        # PFL: a signal changes while the job is ready and PFL is active
        job_ready, pfl_event = self._edges(r.ros_ready, r.pfl)
        if r.ros_ready != last.ros_ready and not r.ros_ready:
            cleared.append("OT#889 fell")
        self._job_ready = job_ready
        if pfl_event:
            self._pfl_during_move = True
            cleared.append("PFL event")
        self._r = r
        if cleared:
            queues = self._queues
            if queues.has_queued_motion() or queues.any_pending():
                logger.info("queues cleared by the status monitor: %s", ", ".join(cleared))
            queues.clear()
        self._refresh()

    @property
    def pfl_active(self) -> bool:
        """§4.1: only with the PFL option on YRC1000 / YRC1000micro builds."""
        if not self.pfl_option:
            return False
        return self._pfl_during_move or pfl_signals_active(self._r.pfl)

    @property
    def estopped(self) -> bool:
        return not all(self._r.estop_ok)

    @property
    def in_error(self) -> bool:
        return any(self._r.alarm_bits)

    @property
    def servo_reading(self) -> tuple[bool, bool]:
        """(50073, 50727) as the status monitor last read them."""
        return bool(self._r.servo), bool(self._r.eco)

    @property
    def play_reading(self) -> bool:
        return bool(self._r.play)

    # ================================================================== NOT_READY (§4.2)

    def not_ready_subcode(self) -> NotReadySubcode:
        """§4.2: the first matching test wins, in this order."""
        if any(self._r.alarm_bits):
            return NotReadySubcode.ALARM
        if self._r.error:
            return NotReadySubcode.ERROR
        if self.estopped:
            return NotReadySubcode.ESTOP
        if not self._r.play:
            return NotReadySubcode.NOT_PLAY
        if not self._r.remote:
            return NotReadySubcode.NOT_REMOTE
        if not self._r.servo or self._r.eco:
            return NotReadySubcode.SERVO_OFF
        if self._r.hold:
            return NotReadySubcode.HOLD
        if self.pfl_active:
            return NotReadySubcode.PFL_ACTIVE
        if self.inc_move_error:
            return NotReadySubcode.INC_MOVE_ERROR
        if not self._r.operating:
            return NotReadySubcode.NOT_STARTED
        if not self._r.ros_ready:
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

    def not_ready_why(self, sub: NotReadySubcode) -> str:
        """The specifics behind ``sub`` and what clears it (the web pendant shows it)."""
        return self._not_ready_why(sub)

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
            return "eco mode" if self._r.eco else "START_TRAJ_MODE switches servo power on"
        if sub is NotReadySubcode.HOLD:
            return "release HOLD, then START_TRAJ_MODE restarts INIT_ROS"
        if sub is NotReadySubcode.PFL_ACTIVE:
            active = [
                name
                for name, on in zip(
                    ("PFL stop", "PFL escape", "avoiding", "avoid joint", "avoid translation"),
                    self._r.pfl,
                    strict=True,
                )
                if on
            ]
            now = ", ".join(active) if active else "PFL signals clear, the event is latched"
            return f"{now}; START_TRAJ_MODE clears the latch"
        if sub is NotReadySubcode.INC_MOVE_ERROR:
            return f"{self._inc_move_error_reason}; START_TRAJ_MODE clears it"
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
        if self._dx100 and not self._skill_flags[0]:
            reasons.append('SKILLSND "ROS-START" not received for slave 1')
        if self._dx100 and self._num_groups > 1 and not self._skill_flags[1]:
            reasons.append('SKILLSND "ROS-START" not received for slave 2')
        if not self._job_ready:
            reasons.append("OT#889 is on but its rising edge was not seen")
        if self._stop_flag:
            reasons.append("a stop is in progress")
        return "; ".join(reasons)


def pfl_signals_active(pfl: tuple[int, ...]) -> bool:
    stop, escape, avoiding, avoid_joint, avoid_translation = pfl
    return bool(stop or escape or (avoiding and (avoid_joint or avoid_translation)))
