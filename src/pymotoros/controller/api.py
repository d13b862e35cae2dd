"""What the network layer may ask of the virtual controller, as protocols.

The servers (``pymotoros.runtime``) translate wire messages into these calls and
the results back into wire replies; the controller never sees bytes. Expected
refusals are values (:class:`Outcome` with a NOT_READY or INVALID result), never
exceptions.

Some MotoROS commands take controller time (START_TRAJ_MODE polls every 50 ms for
up to 5 s; START_SERVOS waits for servo power). Those return a :class:`Pending`
that the controller completes during a later :meth:`MotoRosController.tick`; the
caller either keeps ticking (tests, plain loop) or awaits a future resolved by a
done-callback (servers). Nothing here knows about asyncio or the wall clock.

The values these calls exchange (:class:`Outcome`, :class:`ControllerSnapshot` and every
part of it, ...) are declared in the leaf :mod:`pymotoros.controller.values` and
re-exported here; this module adds the protocols, which name the controller's parts
(the safety unit, the client lint, the alarm history) and so sit above them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, Unpack

import pymotoros.protocol.constants as constants
from pymotoros.controller.alarms import Alarm
from pymotoros.controller.lint import ClientLint, ResumedMotion
from pymotoros.controller.operator_keys import OperatorKeys
from pymotoros.controller.safety import SafetyTarget
from pymotoros.controller.safety.fsu import FsuRequest
from pymotoros.controller.values import (
    INLINE,
    MOTOROS_FIRST_OUTPUT,
    MOTOROS_OUTPUT_COUNT,
    OMIT,
    AlarmInfo,
    ContactInfo,
    ControllerSnapshot,
    FeedbackData,
    FiredEventInfo,
    GroupSnapshot,
    IoRead,
    JobPosition,
    NotReadyInfo,
    OperatorSnapshot,
    Outcome,
    Pending,
    PointData,
    Scenario,
    StatusData,
    TcpSnapshot,
    WorkspaceSnapshot,
    described,
)
from pymotoros.models.fidelity import Fidelity
from pymotoros.protocol.constants import IoResultCode

__all__ = [
    "INLINE",
    "MOTOROS_FIRST_OUTPUT",
    "MOTOROS_OUTPUT_COUNT",
    "OMIT",
    "AlarmInfo",
    "ContactInfo",
    "ControllerSnapshot",
    "FaultInjection",
    "FeedbackData",
    "FiredEventInfo",
    "GroupSnapshot",
    "IoRead",
    "JobPosition",
    "MotoRosController",
    "NotReadyInfo",
    "OperatorPanel",
    "OperatorSnapshot",
    "Outcome",
    "Pending",
    "PointData",
    "SafetyPanel",
    "StatusData",
    "TcpSnapshot",
    "WorkspaceSnapshot",
    "described",
]


class MotoRosController(Protocol):
    """The controller as the servers see it. ``VirtualController`` implements it."""

    @property
    def period_ms(self) -> int:
        """The interpolation period (ms)."""
        ...

    @property
    def num_groups(self) -> int: ...

    @property
    def time_ms(self) -> int:
        """Controller time since boot (ms): the time line of the lint's findings."""
        ...

    lint: ClientLint
    """What clients did that a real controller answers differently (issue 31)."""

    def tick(self) -> None:
        """Advance controller time by exactly one interpolation period."""
        ...

    # --- motion port
    def motion_ctrl(self, group_no: int, command: int) -> Outcome | Pending: ...

    def trajectory_point(self, sequence: int, point: PointData) -> Outcome | Pending: ...

    def trajectory_point_ex(
        self, sequence: int, points: Sequence[PointData]
    ) -> Outcome | Pending: ...

    def select_tool(self, group_no: int, tool: int) -> Outcome: ...

    def dh_parameters(self) -> tuple[tuple[tuple[float, float, float, float], ...], ...] | None:
        """4 groups × 8 links × (theta, d, a, alpha); None if the library read fails."""
        ...

    # --- IO port (bit and group also on the motion port)
    def read_io_bit(self, address: int) -> IoRead: ...

    def write_io_bit(self, address: int, value: int) -> IoResultCode: ...

    def read_io_group(self, address: int) -> IoRead: ...

    def write_io_group(self, address: int, value: int) -> IoResultCode: ...

    def read_mregister(self, number: int) -> IoRead: ...

    def write_mregister(self, number: int, value: int) -> IoResultCode: ...

    # --- connections (the servers report them; MotoROS mirrors them on OT#893..895)
    def motion_connected(self) -> ResumedMotion | None:
        """Not None when a closed connection's queued increments resume now (exact,
        §2.2), or would on a robot (safe cleared them: ``cleared_s``)."""
        ...

    def motion_disconnected(self) -> None:
        """The motion tasks end; the queues are kept (fidelity exact, as MotoROS 1.9.12,
        §2.2) or cleared (safe)."""
        ...

    @property
    def fidelity(self) -> Fidelity:
        """exact or safe (``[motoros] fidelity``, docs/fidelity.md): what the servers copy."""
        ...

    def state_clients_changed(self, count: int) -> None: ...

    def io_connected(self) -> None: ...

    def has_queued_motion(self) -> bool:
        """Any group queue holds increments: decides the connection-replacement rule (§2.2)."""
        ...

    # --- state server
    def joint_feedback(self, group_no: int) -> FeedbackData: ...

    def robot_status(self) -> StatusData: ...

    def snapshot(self) -> ControllerSnapshot: ...


class OperatorPanel(Protocol):
    """The operator's hands: pendant keys, E-stop button, mode switch, forced IO.

    Used by the HTTP control API and by tests. Invalid arguments raise ``ValueError``
    with a message that says what was wrong (e.g. an address outside every IO range);
    legal actions never raise, whatever the state (pressing E-stop twice is fine).
    """

    @property
    def keys(self) -> OperatorKeys:
        """The pendant's keys themselves: an operator action with state of its own
        (``controller/actions.py``) calls its key here, so a new key needs no method on
        this protocol or the facade."""
        ...

    def press_estop(self, pressed: bool) -> None:
        """Pendant E-stop: cuts servo power and stops the job; raises no alarm."""
        ...

    def set_hold(self, on: bool) -> None: ...

    def set_mode(self, mode: constants.PendantMode) -> None: ...

    def set_remote(self, on: bool) -> None: ...

    def set_servo(self, on: bool) -> None:
        """Servo power request as from the pendant (refused silently while E-stopped)."""
        ...

    def set_eco(self, on: bool) -> None:
        """Enter eco mode (needs servo on) or leave it."""
        ...

    def raise_alarm(self, code: int, subcode: int, text: str) -> None: ...

    def alarm_history(self) -> tuple[Alarm, ...]:
        """The last alarms and operator errors raised, oldest first (a bounded history)."""
        ...

    def alarms_raised(self) -> int:
        """Alarms and operator errors raised since boot, however many the history keeps
        (``GET /metrics``'s ``pymotoros_alarms_total``)."""
        ...

    def reset(self) -> None:
        """The pendant's RESET key: clears alarms and errors whose cause is gone."""
        ...

    def force_io(self, address: int, value: int) -> None:
        """Force any bit address to 0/1, or an M-register (address 1000000 + n) to 0..65535.

        Unlike a client's write, any readable area may be forced (inputs, specific
        outputs, control status …): this is the operator simulating the cell.
        """
        ...


class FaultInjection(Protocol):
    """Faults the operator can inject beyond the pendant's keys (HTTP ``/api/error``,
    ``/api/io/failure``, ``/api/drop_motion``). ``VirtualController`` implements it."""

    def raise_error(self, code: int, subcode: int = 0, text: str = "") -> None:
        """An operator error (50014): refuses motion with 5002 until reset; not an alarm."""
        ...

    def set_io_api_failure(self, *, reads: bool = False, writes: bool = False) -> None:
        """Make client IO reads (1004) and/or writes (1005) fail."""
        ...

    def drop_motion(self) -> None:
        """Close the motion connection as a pulled cable (ValueError when none is attached)."""
        ...


class SafetyPanel(SafetyTarget, Protocol):
    """The cell's safety functions as the operator drives them (HTTP ``/api/pfl``,
    ``/api/fsu``, ``/api/scenario``): what their actions act on
    (:class:`~pymotoros.controller.safety.SafetyTarget`: the safety unit and the PFL
    event), scenarios and the FSU's limits. ``VirtualController`` implements it;
    refusals raise ``ValueError`` saying why."""

    def load_scenario(self, scenario: Scenario) -> None:
        """Run a scenario's timed events from the next tick."""
        ...

    def set_fsu(self, **request: Unpack[FsuRequest]) -> None:
        """Switch the FSU speed limits at run time (the arguments: :class:`FsuRequest`)."""
        ...
