"""Why motion is not ready: the NOT_READY subcode order and its specifics (reference §4.2).

:class:`NotReadyReasons` answers CHECK_MOTION_READY's refusal: the first matching test
of §4.2 wins, and the detail says what holds the robot (the specifics found here: which
alarm, which E-stop chain, where INIT_ROS is) and what clears it: the remedy the reason
declares (``NotReadySubcode.remedy``, the text the client and ``pymotoros status`` show
too). The web pendant shows the same words.
"""

from __future__ import annotations

from collections.abc import Callable

from pymotoros.controller.api import Outcome
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.ready_flags import ReadyFlags
from pymotoros.controller.replies import reply
from pymotoros.protocol.constants import NotReadySubcode, ResultCode

_PFL_NAMES = ("PFL stop", "PFL escape", "avoiding", "avoid joint", "avoid translation")


class NotReadyReasons:
    """The §4.2 order over the status monitor's last reading and MotoROS's flags."""

    def __init__(self, ctx: MotoRosContext, flags: ReadyFlags) -> None:
        self._machine = ctx.machine
        self._runner = ctx.runner
        self._flags = flags
        self._specifics: dict[NotReadySubcode, Callable[[], str]] = {
            NotReadySubcode.ALARM: self._alarm,
            NotReadySubcode.ERROR: self._error,
            NotReadySubcode.ESTOP: self._estop,
            NotReadySubcode.SERVO_OFF: self._servo_off,
            NotReadySubcode.PFL_ACTIVE: self._pfl,
            NotReadySubcode.INC_MOVE_ERROR: lambda: flags.latches.inc_move_error_reason,
            NotReadySubcode.WAITING_ROS: self._waiting_ros,
            NotReadySubcode.SKILLSEND: self._skill_detail,
        }

    def subcode(self) -> NotReadySubcode:
        """§4.2: the first matching test wins, in this order."""
        flags = self._flags
        r = flags.reading
        tests = (
            (r.in_error, NotReadySubcode.ALARM),
            (r.error, NotReadySubcode.ERROR),
            (r.estopped, NotReadySubcode.ESTOP),
            (not r.play, NotReadySubcode.NOT_PLAY),
            (not r.remote, NotReadySubcode.NOT_REMOTE),
            (not r.servo or r.eco, NotReadySubcode.SERVO_OFF),
            (r.hold, NotReadySubcode.HOLD),
            (flags.pfl_active, NotReadySubcode.PFL_ACTIVE),
            (flags.latches.inc_move_error, NotReadySubcode.INC_MOVE_ERROR),
            (not r.operating, NotReadySubcode.NOT_STARTED),
            (not r.ros_ready, NotReadySubcode.WAITING_ROS),
            (not flags.motion_ready, NotReadySubcode.SKILLSEND),
        )
        return next((sub for failed, sub in tests if failed), NotReadySubcode.UNSPECIFIED)

    def outcome(
        self, result: ResultCode = ResultCode.NOT_READY, group_no: int | None = None
    ) -> Outcome:
        """The refusal MotoROS sends: ``result`` with the subcode and its specifics."""
        sub = self.subcode()
        detail = f"not ready for motion: {int(sub)} {sub.name}: {sub.meaning}"
        why = self.why(sub)
        if why:
            detail += f" ({why})"
        return reply(result, int(sub), detail, group_no=group_no)

    def why(self, sub: NotReadySubcode) -> str:
        """The specifics behind ``sub`` and its declared remedy ("" for UNSPECIFIED,
        which the controller answers when motion is ready)."""
        if sub is NotReadySubcode.UNSPECIFIED:
            return ""
        specifics = self.specifics(sub)
        return f"{specifics}; {sub.remedy}" if specifics else sub.remedy

    def specifics(self, sub: NotReadySubcode) -> str:
        """What holds the robot, as this controller sees it ("" when the meaning says it
        all): the alarms, the E-stop chains, the PFL signals, where INIT_ROS is …"""
        explain = self._specifics.get(sub)
        return explain() if explain is not None else ""

    def _alarm(self) -> str:
        state = self._machine.state
        alarms = ", ".join(f"{a.code}/{a.subcode} {a.text}".strip() for a in state.alarms)
        return alarms or "alarm output on"

    def _error(self) -> str:
        errors = ", ".join(f"{e.code} {e.text}".strip() for e in self._machine.state.errors)
        return errors or "error output on"

    def _estop(self) -> str:
        estop = sorted(self._machine.state.estop, key=lambda e: e.value)
        chains = ", ".join(e.name.lower() for e in estop)
        return f"{chains or 'an'} E-stop pressed"

    def _servo_off(self) -> str:
        return "eco mode" if self._flags.reading.eco else ""

    def _pfl(self) -> str:
        pfl = self._flags.reading.pfl
        active = [name for name, on in zip(_PFL_NAMES, pfl, strict=True) if on]
        return ", ".join(active) if active else "PFL signals clear, the event is latched"

    def _waiting_ros(self) -> str:
        where = ", ".join(f"{job} line {line}" for job, line in self._runner.position())
        return f"INIT_ROS at {where or 'its start'}; OT#889 not on yet"

    def _skill_detail(self) -> str:
        flags = self._flags
        reasons = [
            f'SKILLSND "ROS-START" not received for slave {slave}'
            for slave in flags.missing_skills()
        ]
        if not flags.latches.job_ready:
            reasons.append("OT#889 is on but its rising edge was not seen")
        if flags.latches.stopping:
            reasons.append("a stop is in progress")
        return "; ".join(reasons)
