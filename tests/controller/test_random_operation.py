"""Random operator actions and client requests: no exception, invariants always hold."""

from __future__ import annotations

from collections.abc import Callable

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pymotoros.controller import PendantMode, VirtualController, cell_from_dict
from pymotoros.controller.signals import PFL_STOP
from pymotoros.protocol.constants import MotionCommand

from .helpers import point
from .states import settle_monitor


def _here(vc: VirtualController) -> list[float]:
    return list(vc.snapshot().groups[0].command_rad)


def _move(vc: VirtualController, seq: int) -> None:
    here = _here(vc)
    vc.trajectory_point(0, point(0, 0.0, here))
    vc.trajectory_point(seq, point(0, 0.2 * seq, [q + 0.05 for q in here]))


def _pfl(vc: VirtualController, value: int) -> None:
    if vc.cell.controller.pfl_signals:  # 81702 exists on YRC1000 / YRC1000micro only
        vc.force_io(PFL_STOP, value)


ACTIONS: dict[str, Callable[[VirtualController], object]] = {
    "estop": lambda vc: vc.press_estop(True),
    "release": lambda vc: vc.press_estop(False),
    "hold": lambda vc: vc.set_hold(True),
    "unhold": lambda vc: vc.set_hold(False),
    "teach": lambda vc: vc.set_mode(PendantMode.TEACH),
    "play": lambda vc: vc.set_mode(PendantMode.PLAY),
    "remote off": lambda vc: vc.set_remote(False),
    "remote on": lambda vc: vc.set_remote(True),
    "servo on": lambda vc: vc.set_servo(True),
    "servo off": lambda vc: vc.set_servo(False),
    "eco": lambda vc: vc.set_eco(True),
    "alarm": lambda vc: vc.raise_alarm(4100, 0, "minor"),
    "major alarm": lambda vc: vc.raise_alarm(1000, 0, "major"),
    "error": lambda vc: vc.raise_error(2010),
    "reset": lambda vc: vc.reset(),
    "pfl on": lambda vc: _pfl(vc, 1),
    "pfl off": lambda vc: _pfl(vc, 0),
    "disconnect": lambda vc: vc.motion_disconnected(),
    "move": lambda vc: _move(vc, 1),
    **{
        c.name: (lambda vc, c=c: vc.motion_ctrl(0, c))  # type: ignore[misc]
        for c in MotionCommand
    },
}


CELLS: dict[str, Callable[[], VirtualController]] = {
    "hc10 yrc1000": VirtualController,
    "two arms dx100": lambda: VirtualController(
        cell_from_dict(
            {"controller": {"model": "dx100"}, "groups": [{"robot": "mh5"}, {"robot": "mh5"}]}
        )
    ),
    "sda10f fs100 with FSU": lambda: VirtualController(
        cell_from_dict(
            {
                "controller": {"model": "fs100", "fsu_speed_limit_pct": 40},
                "robot": {"model": "sda10f"},
            }
        )
    ),
}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.sampled_from(sorted(CELLS)),
    st.lists(
        st.tuples(st.sampled_from(sorted(ACTIONS)), st.integers(min_value=0, max_value=80)),
        max_size=25,
    ),
)
def test_invariants(cell: str, actions: list[tuple[str, int]]) -> None:
    vc = CELLS[cell]()
    for name, ticks in actions:
        ACTIONS[name](vc)
        vc.run_ticks(ticks)
        snap = vc.snapshot()
        if snap.estop:
            assert not snap.servo
        if snap.estop or snap.hold or snap.mode is PendantMode.TEACH or not snap.servo:
            assert vc.job_position == ()
        # the snapshot is never stale: it says what the monitor's next run will find
        predicted = snap.motion_ready
        vc.motoros.status_update()
        assert vc.motoros.motion_ready == predicted, name
        settle_monitor(vc)
        status = vc.robot_status()
        mr = vc.motoros
        if mr.motion_ready:
            assert vc.job_position != ()
            assert vc.snapshot().remote
        elif not mr.waiting:
            # every way of losing motion-ready clears the queues
            assert not vc.has_queued_motion(), name
        assert status.motion_possible == int(mr.motion_ready)
        assert status.e_stopped == int(vc.snapshot().estop)
        assert status.in_error == int(bool(vc.snapshot().alarms))
        assert status.mode in (1, 2)
        assert status.in_motion in (0, 1)
