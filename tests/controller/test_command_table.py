"""Every (controller state × motion-port request) pair, with the reply the reference gives.

The expectations are written from reference §3.1–§3.5, §4.1–§4.2 and §5.8, state by
state, not read off the implementation:

* not motion-ready → CHECK_MOTION_READY answers 2 (FALSE) with the §4.2 subcode, and
  trajectory points (types 14 and 2016, any sequence) 5 (NOT_READY) with that subcode;
* an operator error (50014) is not part of the motion-ready flag (§4.1), so a running
  INIT_ROS keeps accepting points while it is shown;
* CHECK_QUEUE_CNT, STOP_MOTION, STOP_SERVOS, RESET_ALARM, STOP_TRAJ_MODE (queues empty),
  DISCONNECT and SELECT_TOOL have no readiness condition;
* START_TRAJ_MODE fails with 5/subcode when it needs an operator (E-stop, hold, not
  remote), when another job runs (step 3), or when INIT_ROS cannot start (TEACH);
  it resets alarms and clears the PFL and inc-move latches itself;
* START_SERVOS fails (2/0, after its 5 s of polling) only when servo power cannot come
  on: E-stop pressed or an alarm active;
* an unknown command gets INVALID/3006 (our fix of a stale reply, docs/fidelity.md).
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from pymotoros.controller import Outcome, VirtualController
from pymotoros.protocol.constants import InvalidSubcode as Inv
from pymotoros.protocol.constants import NotReadySubcode as Nr
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, complete, point
from .states import STATES

UNKNOWN_COMMAND = 200199


def _here(vc: VirtualController) -> list[float]:
    return list(vc.snapshot().groups[0].command_rad)


REQUESTS: dict[str, Callable[[VirtualController], Outcome]] = {
    "CHECK_MOTION_READY": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.CHECK_MOTION_READY)),
    "CHECK_QUEUE_CNT": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.CHECK_QUEUE_CNT)),
    "STOP_MOTION": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.STOP_MOTION)),
    "START_SERVOS": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.START_SERVOS)),
    "STOP_SERVOS": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.STOP_SERVOS)),
    "RESET_ALARM": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.RESET_ALARM)),
    "START_TRAJ_MODE": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.START_TRAJ_MODE)),
    "STOP_TRAJ_MODE": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.STOP_TRAJ_MODE)),
    "DISCONNECT": lambda vc: complete(vc, vc.motion_ctrl(0, CMD.DISCONNECT)),
    "unknown command": lambda vc: complete(vc, vc.motion_ctrl(0, UNKNOWN_COMMAND)),
    "point seq 0": lambda vc: complete(vc, vc.trajectory_point(0, point(0, 0.0, _here(vc)))),
    "point seq 1": lambda vc: complete(vc, vc.trajectory_point(1, point(0, 0.5, _here(vc)))),
    "point seq -1": lambda vc: complete(vc, vc.trajectory_point(-1, point(0, 0.5, _here(vc)))),
    "point_ex seq 0": lambda vc: complete(
        vc, vc.trajectory_point_ex(0, [point(0, 0.0, _here(vc))])
    ),
    "SELECT_TOOL 1": lambda vc: vc.select_tool(0, 1),
}

OK = (R.SUCCESS, 0)
FAIL = (R.FAILURE, 0)


def _not_ready_row(sub: Nr, start_traj: tuple[int, int]) -> dict[str, tuple[int, int]]:
    return {
        "CHECK_MOTION_READY": (R.FALSE, sub),
        "START_TRAJ_MODE": start_traj,
        "point seq 0": (R.NOT_READY, sub),
        "point seq 1": (R.NOT_READY, sub),
        "point seq -1": (R.NOT_READY, sub),
        "point_ex seq 0": (R.NOT_READY, sub),
    }


_READY_ROW = {
    "CHECK_MOTION_READY": OK,
    "START_TRAJ_MODE": OK,
    "point seq 0": OK,
    "point seq 1": OK,
    "point seq -1": (R.INVALID, Inv.SEQUENCE),
    "point_ex seq 0": OK,
}

# state → the rows that differ from the defaults below
EXPECTED: dict[str, dict[str, tuple[int, int]]] = {
    "boot": _not_ready_row(Nr.SERVO_OFF, OK),
    "ready": _READY_ROW,
    "estop": {
        **_not_ready_row(Nr.ESTOP, (R.NOT_READY, Nr.ESTOP)),
        "START_SERVOS": FAIL,
    },
    "hold": _not_ready_row(Nr.HOLD, (R.NOT_READY, Nr.HOLD)),
    "teach": _not_ready_row(Nr.NOT_PLAY, (R.NOT_READY, Nr.NOT_PLAY)),
    "not_remote": _not_ready_row(Nr.NOT_REMOTE, (R.NOT_READY, Nr.NOT_REMOTE)),
    "alarm": {**_not_ready_row(Nr.ALARM, OK), "START_SERVOS": FAIL},
    "error": _READY_ROW,
    "pfl": _not_ready_row(Nr.PFL_ACTIVE, OK),
    "inc_move_error": _not_ready_row(Nr.INC_MOVE_ERROR, OK),
    "job_not_running": _not_ready_row(Nr.NOT_STARTED, OK),
    "waiting_ros": _not_ready_row(Nr.WAITING_ROS, (R.NOT_READY, Nr.WAITING_ROS)),
}

DEFAULTS: dict[str, tuple[int, int]] = {
    "CHECK_QUEUE_CNT": OK,  # count 0 in the subcode: nothing is queued in these states
    "STOP_MOTION": OK,
    "START_SERVOS": OK,
    "STOP_SERVOS": OK,
    "RESET_ALARM": OK,
    "STOP_TRAJ_MODE": OK,
    "DISCONNECT": OK,
    "unknown command": (R.INVALID, Inv.COMMAND),
    "SELECT_TOOL 1": OK,
}


def test_the_table_is_complete() -> None:
    assert set(EXPECTED) == set(STATES)
    for state, row in EXPECTED.items():
        assert set(row) | set(DEFAULTS) == set(REQUESTS), state


@pytest.mark.parametrize("request_name", list(REQUESTS))
@pytest.mark.parametrize("state", list(STATES))
def test_reply(state: str, request_name: str) -> None:
    vc = STATES[state]()
    expected = EXPECTED[state].get(request_name, DEFAULTS.get(request_name))
    outcome = REQUESTS[request_name](vc)
    assert (outcome.result, outcome.subcode) == expected, outcome.detail
    if outcome.result != R.SUCCESS:
        assert outcome.detail, "a refusal explains itself"
    assert outcome.close_connection == (request_name == "DISCONNECT")
