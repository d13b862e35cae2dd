"""A NOT_READY reason carries its own remedy (issue 30), and the remedy is true.

Each ``NotReadySubcode`` declares its remedy once; the client's error, ``pymotoros
status``, the controller's refusal and the web pendant show that text. The twin checks
each claim: START_TRAJ_MODE alone clears exactly the reasons whose remedy says so, and is
refused for the ones that need an operator first (an E-stop, HOLD, REMOTE, PLAY, a PFL
stop); before, the controller told a PFL stop "START_TRAJ_MODE clears the latch".
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pymotoros.cli.live import not_ready_reason
from pymotoros.client.errors import NotReadyError, reply_error
from pymotoros.client.state import Mode, Status
from pymotoros.controller import VirtualController
from pymotoros.controller.assembly import assemble
from pymotoros.controller.cell import default_cell
from pymotoros.controller.readiness import Readiness
from pymotoros.protocol.constants import (
    OPERATOR_FIRST,
    MotionCommand,
    NotReadySubcode,
    PendantMode,
    ResultCode,
)

from .helpers import CMD, command, enter_traj_mode, point, send, start_at_current

Nr = NotReadySubcode


@pytest.mark.parametrize("sub", list(Nr))
def test_the_client_error_shows_the_declared_remedy(sub: NotReadySubcode) -> None:
    assert sub.remedy, f"{sub.name} declares no remedy"
    err = reply_error(ResultCode.NOT_READY, sub, MotionCommand.START_TRAJ_MODE)
    assert isinstance(err, NotReadyError)
    assert err.remedy == sub.remedy
    assert str(err).endswith(f"What to do: {sub.remedy}")


@pytest.mark.parametrize("sub", [s for s in Nr if s is not Nr.UNSPECIFIED])
def test_the_controller_explains_each_reason_with_its_declared_remedy(
    sub: NotReadySubcode,
) -> None:
    ctx = assemble(default_cell(), seed=0, on_skill=lambda slave, text: None).ctx
    reasons = Readiness(ctx).reasons
    assert reasons.why(sub).endswith(sub.remedy)


def test_operator_first_remedies_do_not_promise_start_traj_mode() -> None:
    """A reason START_TRAJ_MODE cannot clear begins with the operator's hand; the others
    do not send the user to an operator."""
    for sub in Nr:
        before_start = sub.remedy.split("START_TRAJ_MODE")[0]
        if sub in OPERATOR_FIRST:
            assert before_start.startswith("an operator must"), sub.name
        else:
            assert "an operator must" not in sub.remedy, sub.name


def _status(**fields: object) -> Status:
    base: dict[str, object] = {
        "drives_powered": True,
        "e_stopped": False,
        "error_code": 0,
        "in_error": False,
        "in_motion": False,
        "mode": Mode.PLAY,
        "motion_possible": False,
    }
    base.update(fields)
    return Status(**base)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("sub", "fields"),
    [
        (Nr.ESTOP, {"e_stopped": True, "drives_powered": False}),
        (Nr.ALARM, {"in_error": True, "error_code": 4315}),
        (Nr.NOT_PLAY, {"mode": Mode.TEACH}),
        (Nr.SERVO_OFF, {"drives_powered": False}),
        (Nr.NOT_STARTED, {}),
    ],
)
def test_pymotoros_status_shows_the_declared_remedy(
    sub: NotReadySubcode, fields: dict[str, object]
) -> None:
    reason = not_ready_reason(_status(**fields))
    assert reason.startswith(f"{sub.name} ({int(sub)}): {sub.meaning}")
    assert reason.endswith(f"; {sub.remedy}")


def _alarm(vc: VirtualController) -> None:
    vc.raise_alarm(4315, 1, "COLLISION DETECT")


def _pfl_stop(vc: VirtualController) -> None:
    assert start_at_current(vc).ok
    assert send(vc, 1, point(0, 2.0, [0.5, 0, 0, 0, 0, 0])).ok
    vc.run_ticks(50)
    vc.pfl_event("contact", stop_ms=60_000)  # held until an operator releases it


STATES: dict[NotReadySubcode, Callable[[VirtualController], None]] = {
    Nr.ALARM: _alarm,
    Nr.ERROR: lambda vc: vc.raise_error(1234, 0, "from a test"),
    Nr.ESTOP: lambda vc: vc.press_estop(True),
    Nr.NOT_PLAY: lambda vc: vc.set_mode(PendantMode.TEACH),
    Nr.NOT_REMOTE: lambda vc: vc.set_remote(False),
    Nr.SERVO_OFF: lambda vc: vc.set_servo(False),
    Nr.HOLD: lambda vc: vc.set_hold(True),
    Nr.PFL_ACTIVE: _pfl_stop,
    Nr.INC_MOVE_ERROR: lambda vc: vc.motoros.latch_inc_move_error("refused: -3"),
    Nr.NOT_STARTED: lambda vc: command(vc, CMD.STOP_TRAJ_MODE),
}


@pytest.mark.parametrize("sub", list(STATES))
def test_each_reason_on_the_twin_is_told_with_its_remedy_and_the_remedy_is_true(
    sub: NotReadySubcode,
) -> None:
    vc = VirtualController()
    if sub is not Nr.ERROR:  # an operator error alone leaves motion-ready on (§4.1)
        enter_traj_mode(vc)
    STATES[sub](vc)
    vc.run_ticks(5)  # the 10 ms status monitor has seen it
    check = command(vc, CMD.CHECK_MOTION_READY)
    assert check.subcode == sub
    assert check.detail.endswith(f"{sub.remedy})")  # the controller's refusal text
    shown = vc.snapshot().not_ready  # the web pendant's line
    assert shown is not None
    assert (shown.subcode, shown.why.endswith(sub.remedy)) == (int(sub), True)
    # what the remedy says of START_TRAJ_MODE holds: alone it clears the reason, or it
    # is refused until an operator has acted
    started = command(vc, CMD.START_TRAJ_MODE)
    if sub in OPERATOR_FIRST:
        assert (started.ok, started.subcode) == (False, sub)
    else:
        assert started.ok, started
