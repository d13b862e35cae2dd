"""What the network layer may ask of the virtual controller, as types.

The servers (``pymotoros.runtime``) translate wire messages into these calls and
the results back into wire replies; the controller never sees bytes. Expected
refusals are values (:class:`Outcome` with a NOT_READY or INVALID result), never
exceptions.

Some MotoROS commands take controller time (START_TRAJ_MODE polls every 50 ms for
up to 5 s; START_SERVOS waits for servo power). Those return a :class:`Pending`
that the controller completes during a later :meth:`MotoRosController.tick`; the
caller either keeps ticking (tests, plain loop) or awaits a future resolved by a
done-callback (servers). Nothing here knows about asyncio or the wall clock.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Final, Protocol, Unpack

from pymotoros.models.fidelity import Fidelity
from pymotoros.models.workspace import Obstacle
from pymotoros.protocol.constants import IoResultCode, ResultCode
from pymotoros.protocol.constants import PendantMode as PendantMode  # its old home

if TYPE_CHECKING:
    from pymotoros.controller.alarms import Alarm
    from pymotoros.controller.cell import CellConfig
    from pymotoros.controller.lint import ClientLint, ResumedMotion
    from pymotoros.controller.safety import SafetySnapshot, SafetyUnit
    from pymotoros.controller.safety.fsu import FsuRequest
    from pymotoros.controller.scenario import Scenario


@dataclass(frozen=True, slots=True)
class Outcome:
    """The controller's answer to one motion-port request."""

    result: ResultCode
    subcode: int = 0
    group_no: int | None = None
    """Group to put in the reply when it is not the request's (FULL_EX: the last group
    processed, §3.5); None means echo the request."""
    close_connection: bool = False
    """DISCONNECT succeeded, or GET_DH_PARAMETERS failed: close without replying (§3.1, §5.9)."""
    detail: str = ""
    """Human explanation with the numbers behind a refusal (point, axis, requested vs
    allowed, the subcode's meaning). Logged by the server; never on the wire."""

    @property
    def ok(self) -> bool:
        return self.result == ResultCode.SUCCESS


class Pending:
    """A motion-port request that completes after some controller ticks.

    ``add_done_callback`` callbacks run synchronously inside the tick that completes
    the request (or at once if it is already done).
    """

    __slots__ = ("_callbacks", "_outcome", "description")

    def __init__(self, description: str) -> None:
        self.description = description
        self._outcome: Outcome | None = None
        self._callbacks: list[Callable[[Outcome], None]] = []

    @property
    def done(self) -> bool:
        return self._outcome is not None

    @property
    def outcome(self) -> Outcome:
        if self._outcome is None:
            raise RuntimeError(f"{self.description} has not completed yet")
        return self._outcome

    def complete(self, outcome: Outcome) -> None:
        """Called by the controller, once."""
        if self._outcome is not None:
            raise RuntimeError(f"{self.description} completed twice")
        self._outcome = outcome
        callbacks, self._callbacks = self._callbacks, []
        for callback in callbacks:
            callback(outcome)

    def add_done_callback(self, callback: Callable[[Outcome], None]) -> None:
        if self._outcome is not None:
            callback(self._outcome)
        else:
            self._callbacks.append(callback)


@dataclass(frozen=True, slots=True)
class PointData:
    """One group's part of a trajectory point, as received (values already float32).

    ``pos``/``vel``/``acc`` hold the wire's 10 slots in ROS order.
    """

    group_no: int
    valid_fields: int
    time: float
    pos: tuple[float, ...]
    vel: tuple[float, ...]
    acc: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class IoRead:
    """Value and result code of an IO or M-register read."""

    value: int
    result_code: IoResultCode


@dataclass(frozen=True, slots=True)
class FeedbackData:
    """What one JOINT_FEEDBACK carries (§2.4): ROS order, 10 slots, rad and rad/s."""

    group_no: int
    valid_fields: int
    pos: tuple[float, ...]
    vel: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class StatusData:
    """The seven ROBOT_STATUS fields (§2.6)."""

    drives_powered: int
    e_stopped: int
    error_code: int
    in_error: int
    in_motion: int
    mode: int
    motion_possible: int


@dataclass(frozen=True, slots=True)
class AlarmInfo:
    code: int
    subcode: int
    text: str


@dataclass(frozen=True, slots=True)
class TcpSnapshot:
    """The active tool's TCP in base coordinates (m, rad; R = Rz·Ry·Rx), command and
    feedback, and its speed in mm/s (docs/kinematics.md)."""

    command: tuple[float, float, float, float, float, float]
    feedback: tuple[float, float, float, float, float, float]
    command_speed_mm_s: float
    feedback_speed_mm_s: float


@dataclass(frozen=True, slots=True)
class FiredEventInfo:
    """A scenario event that fired: seconds since boot, action, its parameters, refusal."""

    t: float
    action: str
    params: tuple[tuple[str, object], ...]
    error: str = ""


@dataclass(frozen=True, slots=True)
class NotReadyInfo:
    """Why MotoROS would refuse motion now: what CHECK_MOTION_READY would answer
    (subcode 0 UNSPECIFIED when ready), the subcode's meaning and what clears it."""

    subcode: int
    name: str
    meaning: str
    why: str


@dataclass(frozen=True, slots=True)
class JobPosition:
    """The line a running INFORM job task is at."""

    job: str
    line: int


@dataclass(frozen=True, slots=True)
class ContactInfo:
    """A robot link touching an obstacle at the latest workspace check (docs/workspace.md)."""

    obstacle: str
    """The obstacle's name (for a self-collision: the other link)."""
    link: str
    """The robot link that touches it."""
    group: str
    """The link's control group."""
    depth_mm: float
    """How far the link's shape overlaps the obstacle (mm)."""
    self_collision: bool = False


def _no_obstacles() -> tuple[Obstacle, ...]:
    return ()


@dataclass(frozen=True, slots=True)
class WorkspaceSnapshot:
    """The cell's obstacles now and what the robot touches (issue 21)."""

    obstacles: tuple[Obstacle, ...] = field(default_factory=_no_obstacles)
    """Each obstacle in the cell file's keys: name, one of box/cylinder/sphere, xyz (m),
    rpy_deg, and frame when it is given in another group's frame."""
    contacts: tuple[ContactInfo, ...] = ()
    """What the robot touches now (empty: nothing)."""


MOTOROS_FIRST_OUTPUT: Final = 889
"""OT#889..896: the outputs INIT_ROS and MotoROS use (motoros-1.9.12.md)."""
MOTOROS_OUTPUT_COUNT: Final = 8


@dataclass(frozen=True, slots=True)
class GroupSnapshot:
    name: str
    joint_names: tuple[str, ...]
    command_rad: tuple[float, ...]
    feedback_rad: tuple[float, ...]
    command_pulse: tuple[int, ...]
    queue: int
    """Increments queued for the group."""
    tool: int
    tcp: TcpSnapshot | None = None
    """The active tool's TCP (null: the group has no kinematic chain)."""


OMIT: Final[Mapping[str, str]] = MappingProxyType({"document": "omit"})
"""A snapshot field's metadata: not in the state document (``GET /api/state``), because
the document shows it elsewhere (the pendant's extras, the loop's ``tick``) or it is
fixed at boot (the cell)."""
INLINE: Final[Mapping[str, str]] = MappingProxyType({"document": "inline"})
"""A snapshot field's metadata: its own fields join the document's top level (the safety
unit's part keeps the keys ``fsu`` and ``pfl`` where they have always been)."""


def _no_safety() -> SafetySnapshot:
    # imported here: the safety unit imports the IO image, which imports this module
    from pymotoros.controller.safety import SafetySnapshot

    return SafetySnapshot()


@dataclass(frozen=True, slots=True)
class ControllerSnapshot:
    """An immutable picture of the controller for observers (HTTP API, pendant, tests).

    This is the one declaration of the state document: ``GET /api/state``, the
    ``/ws/state`` feed, the pendant and the control API's OpenAPI schema are derived from
    these fields, their types and their docstrings
    (:mod:`pymotoros.runtime.snapshot_document`). A new field appears in all of them with
    no other edit; metadata :data:`OMIT` keeps one out of the document, :data:`INLINE`
    merges a part's fields into it. A safety function shows its state through
    :attr:`safety`, the part its module fills.
    """

    time_ms: int = field(metadata=OMIT)
    tick_count: int = field(metadata=OMIT)
    mode: PendantMode
    """The pendant's mode switch."""
    remote: bool
    """Remote mode: play commands come from outside (MotoROS needs it)."""
    servo: bool
    """Servo power is on."""
    estop: bool
    """An E-stop is pressed (pendant, external or the cell's)."""
    hold: bool
    """The hold key (or the external hold input) is on."""
    alarms: tuple[AlarmInfo, ...]
    """Active alarms: code, subcode and text."""
    motion_ready: bool
    """Motion-ready as of the current signals: what CHECK_MOTION_READY answers once
    MotoROS's 10 ms status monitor has seen them (never a reading from before the
    latest operator action)."""
    groups: tuple[GroupSnapshot, ...]
    """Every control group, in group order."""
    errors: tuple[AlarmInfo, ...] = field(default=(), metadata=OMIT)
    safety: SafetySnapshot = field(default_factory=_no_safety, metadata=INLINE)
    """What the cell's safety functions show (``controller/safety``): one key each."""
    events: tuple[FiredEventInfo, ...] = ()
    """Scenario events fired: {"t": seconds since boot, "action": ..., its parameters,
    "error" when the controller refused it}."""
    motoros: str = "running"
    """MotoROS's start-up: "running", what it waits for, or why it halted (§2.1, §8)."""
    workspace: WorkspaceSnapshot = field(default_factory=WorkspaceSnapshot)
    """The cell's obstacles (as put and removed at run time) and the contacts now."""
    # What a pendant shows beyond the control API's document (its ``pendant`` extras);
    # None where a controller (a test double) does not model it.
    period_ms: int | None = field(default=None, metadata=OMIT)
    """The interpolation period (ms)."""
    eco: bool | None = field(default=None, metadata=OMIT)
    """Eco mode: servo power saved while idle."""
    not_ready: NotReadyInfo | None = field(default=None, metadata=OMIT)
    """Why motion is not ready now (subcode 0 when it is)."""
    jobs: tuple[JobPosition, ...] | None = field(default=None, metadata=OMIT)
    """The line of every running job task (empty when no job runs)."""
    motoros_outputs: tuple[int, ...] | None = field(default=None, metadata=OMIT)
    """OT#889..896 (:data:`MOTOROS_FIRST_OUTPUT` on), 0 or 1 each."""
    cell: CellConfig | None = field(default=None, metadata=OMIT)
    """The cell the controller was built from (models, tools, groups): fixed at boot."""

    # The names the snapshot had before the safety unit contributed its own part.
    @property
    def fsu_joint_speed_pct(self) -> int | None:
        """The FSU joint-speed limit in force (None: off)."""
        return self.safety.fsu.joint_speed_pct

    @property
    def fsu_tcp_speed_mm_s(self) -> float | None:
        """The FSU TCP-speed limit in force (None: off)."""
        return self.safety.fsu.tcp_speed_mm_s

    @property
    def pfl(self) -> str:
        """The PFL function: "off", "idle", "stop" or "escape"."""
        return self.safety.pfl


def snapshot_names() -> dict[str, object]:
    """The names the snapshot's annotations use from modules this one cannot import at
    load time (an import cycle), for ``typing.get_type_hints(..., localns=...)``."""
    from pymotoros.controller.cell import CellConfig
    from pymotoros.controller.safety import SafetySnapshot

    return {"CellConfig": CellConfig, "SafetySnapshot": SafetySnapshot}


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

    def press_estop(self, pressed: bool) -> None:
        """Pendant E-stop: cuts servo power and stops the job; raises no alarm."""
        ...

    def set_hold(self, on: bool) -> None: ...

    def set_mode(self, mode: PendantMode) -> None: ...

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


class SafetyPanel(Protocol):
    """The cell's safety functions as the operator drives them (HTTP ``/api/pfl``,
    ``/api/fsu``, ``/api/scenario``). ``VirtualController`` implements it; refusals raise
    ``ValueError`` saying why."""

    @property
    def safety(self) -> SafetyUnit:
        """The safety unit itself: a safety function's action (``controller/actions.py``)
        calls its module here, so a new fault needs no facade method."""
        ...

    def load_scenario(self, scenario: Scenario) -> None:
        """Run a scenario's timed events from the next tick."""
        ...

    def pfl_event(self, event: str, *, retreat_ms: int = ..., stop_ms: int = ...) -> None:
        """A PFL "contact" or "clamping" (retreating ``retreat_ms``) now."""
        ...

    def set_fsu(self, **request: Unpack[FsuRequest]) -> None:
        """Switch the FSU speed limits at run time (the arguments: :class:`FsuRequest`)."""
        ...
