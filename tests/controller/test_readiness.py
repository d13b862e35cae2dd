"""Readiness: MotoROS's flags change only through methods that recompute motion-ready."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pymotoros.controller import PendantMode, VirtualController
from pymotoros.protocol.constants import NotReadySubcode as Nr

from .helpers import CMD, command
from .states import ready, settle_monitor


def _check(vc: VirtualController) -> tuple[bool, int]:
    o = command(vc, CMD.CHECK_MOTION_READY)
    return o.ok, o.subcode


def test_a_latch_takes_effect_at_once_and_a_clear_restores_readiness() -> None:
    vc = ready()
    vc.motoros.latch_inc_move_error("test")
    assert not vc.motoros.motion_ready  # no monitor run needed
    assert _check(vc) == (False, Nr.INC_MOVE_ERROR)
    assert vc.robot_status().motion_possible == 0
    vc.motoros.clear_inc_move_error()
    assert vc.motoros.motion_ready
    assert _check(vc)[0]


def test_the_flags_cannot_be_assigned_from_outside() -> None:
    vc = ready()
    for name in ("motion_ready", "job_ready", "inc_move_error", "pfl_during_move"):
        with pytest.raises(AttributeError):
            setattr(vc.motoros, name, False)


@pytest.mark.parametrize(
    ("act", "subcode"),
    [
        (lambda vc: vc.press_estop(True), Nr.ESTOP),
        (lambda vc: vc.set_hold(True), Nr.HOLD),
        (lambda vc: vc.set_mode(PendantMode.TEACH), Nr.NOT_PLAY),
        (lambda vc: vc.set_remote(False), Nr.NOT_REMOTE),
        (lambda vc: vc.raise_alarm(4100, 0, "minor"), Nr.ALARM),
    ],
)
def test_the_snapshot_is_never_behind_while_motoros_keeps_its_10ms_monitor(
    act: Callable[[VirtualController], None], subcode: Nr
) -> None:
    """Between two monitor runs MotoROS still says ready (§2.6 timing is kept), but the
    snapshot already says what CHECK_MOTION_READY will answer after the next run."""
    vc = ready()
    settle_monitor(vc)
    act(vc)
    assert vc.motoros.motion_ready  # the monitor has not run yet
    assert not vc.snapshot().motion_ready
    settle_monitor(vc)
    assert not vc.motoros.motion_ready
    assert _check(vc) == (False, subcode)
    assert vc.snapshot().motion_ready is False
