"""MotoROS's 10 ms status monitor, Ros_Controller_StatusUpdate (reference §2.1, §2.6).

:class:`StatusMonitor` reads the signals MotoROS watches, finds their edges (alarm,
mode/remote/operating/servo loss, OT#889, PFL) and clears the motion queues on the
edges that clear them in MotoROS; it hands each reading to the
:class:`~pymotoros.controller.ready_flags.ReadyFlags`, which computes motion-ready.
"""

from __future__ import annotations

import logging

from pymotoros.controller import signals
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.ready_flags import ReadyFlags
from pymotoros.controller.status_reading import STATUS_PERIOD_MS, StatusReading

logger = logging.getLogger(__name__)

_NO_PFL = (0, 0, 0, 0, 0)


class StatusMonitor:
    """The status monitor's schedule, its reads and its queue-clearing edges."""

    def __init__(self, ctx: MotoRosContext, flags: ReadyFlags) -> None:
        self._io = ctx.io
        self._machine = ctx.machine
        self._queues = ctx.queues
        self._pfl_signals = ctx.cell.controller.pfl_signals
        self._flags = flags
        self._error_code = 0
        self.next_monitor_ms = 0
        """Controller time of the status monitor's next run."""

    @property
    def error_code(self) -> int:
        """ROBOT_STATUS error_code: the first active alarm's number (§2.6)."""
        return self._error_code

    # ================================================================== start-up (§2.1)

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

    # ================================================================== the 10 ms run

    def monitor_tick(self, now_ms: int) -> None:
        """Run the 10 ms status monitor when its period boundary has passed."""
        if now_ms < self.next_monitor_ms:
            return
        while self.next_monitor_ms <= now_ms:
            self.next_monitor_ms += STATUS_PERIOD_MS
        if self._io.monitor_dirty:
            self.status_update()

    def read(self) -> StatusReading:
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
            tuple(get(a) for a in signals.PFL_BITS) if self._pfl_signals else _NO_PFL,
        )

    def edges(self, reading: StatusReading) -> tuple[bool, bool]:
        """(job-ready, PFL event) from the monitor's OT#889 and PFL edges (§2.6, §4.1).

        OT#889's rising edge sets job-ready and its falling edge clears it; a PFL signal
        that changes to active while the job is ready (PFL option on) is a PFL event.
        """
        flags = self._flags
        last = flags.reading
        job_ready = flags.latches.job_ready
        if reading.ros_ready != last.ros_ready:
            job_ready = bool(reading.ros_ready)
        pfl_event = (
            flags.pfl_option and reading.pfl != last.pfl and job_ready and reading.pfl_active
        )
        return job_ready, pfl_event

    def outlook(self) -> bool:
        """The motion-ready flag once the monitor has seen the current signals.

        MotoROS reads its inputs every 10 ms, so the flag may lag an operator action by
        up to one monitor period. This is the same computation on the signals as they
        are now, without the monitor's side effects: what a CHECK_MOTION_READY will
        answer right after the monitor's next run.
        """
        flags = self._flags
        if not self._io.monitor_dirty:
            return flags.motion_ready
        r = self.read()
        job_ready, pfl_event = self.edges(r)
        latched = flags.latches.pfl_during_move or pfl_event
        return flags.ready_for(job_ready, r.operating, r.remote, latched, r.pfl)

    def status_update(self) -> None:
        """Ros_Controller_StatusUpdate: one read of every monitored signal, then the edges."""
        self._io.monitor_dirty = False
        r = self.read()
        last = self._flags.reading
        cleared = [*self._alarm_edge(r, last), *self._mode_edge(r, last)]
        job_ready, pfl_event = self.edges(r)
        if r.ros_ready != last.ros_ready and not r.ros_ready:
            cleared.append("OT#889 fell")
        if pfl_event:
            cleared.append("PFL event")
        if cleared:
            self._clear_queues(cleared)
        self._flags.observe(r, job_ready=job_ready, pfl_event=pfl_event)

    def _alarm_edge(self, r: StatusReading, last: StatusReading) -> list[str]:
        """An alarm edge refreshes error_code; it clears the queues when an alarm is on."""
        if r.alarm_bits == last.alarm_bits:
            return []
        if not r.in_error:
            self._error_code = 0
            return []
        alarms = self._machine.state.alarms
        self._error_code = alarms[0].code if alarms else 0
        return ["alarm"]

    @staticmethod
    def _mode_edge(r: StatusReading, last: StatusReading) -> list[str]:
        """A change of mode, remote, job or servo that leaves motion impossible clears."""
        now = (r.play, r.teach, r.remote, r.operating, r.servo)
        before = (last.play, last.teach, last.remote, last.operating, last.servo)
        lost = r.remote != 1 or r.play != 1 or r.operating == 0 or r.servo == 0
        return ["mode/remote/operating/servo change"] if now != before and lost else []

    def _clear_queues(self, causes: list[str]) -> None:
        queues = self._queues
        if queues.has_queued_motion() or queues.any_pending():
            logger.info("queues cleared by the status monitor: %s", ", ".join(causes))
        queues.clear()
