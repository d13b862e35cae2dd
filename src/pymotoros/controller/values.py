"""The controller's contract as values: what the servers and observers receive.

Every value type the controller hands out (a motion-port :class:`Outcome`, an
:class:`IoRead`, the :class:`ControllerSnapshot` with every part its fields are typed
with, the :class:`CellConfig` it was built from, a :class:`Scenario` it plays) is
declared here, with no behaviour beyond a property. This module is a leaf: it imports
nothing from the rest of :mod:`pymotoros.controller` (only models, the protocol's
constants and the errors), so every part of the controller, the protocols of
:mod:`pymotoros.controller.api` and the runtime's state document can import it, and a
snapshot's type hints resolve without any local namespace.

The state document (``GET /api/state``, ``/ws/state``, the pendant, the OpenAPI schema)
is derived from :class:`ControllerSnapshot` by ``runtime/snapshot_document.py``: a
field's metadata gives its description (:func:`described`) and may keep it out of the
document (:data:`OMIT`) or merge a part's fields into it (:data:`INLINE`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Final, Literal, Protocol

from pymotoros.models import ControllerModel, GroupModel
from pymotoros.models.cell import cell_table
from pymotoros.models.cell_tools import CellTool
from pymotoros.models.fidelity import DEFAULT_FIDELITY, Fidelity
from pymotoros.models.robots import Transform
from pymotoros.models.s1cxg import S1cxgTable
from pymotoros.models.workspace import EMPTY_WORKSPACE, Obstacle, ToolShape, Workspace
from pymotoros.protocol.constants import IoResultCode, PendantMode, ResultCode

OMIT: Final[Mapping[str, str]] = MappingProxyType({"document": "omit"})
"""A snapshot field's metadata: not in the state document (``GET /api/state``), because
the document shows it elsewhere (the pendant's extras, the loop's ``tick``) or it is
fixed at boot (the cell)."""
INLINE: Final[Mapping[str, str]] = MappingProxyType({"document": "inline"})
"""A snapshot field's metadata: its own fields join the document's top level (the safety
unit's part keeps the keys ``fsu`` and ``pfl`` where they have always been)."""


def described(text: str, *more: Mapping[str, str]) -> Mapping[str, str]:
    """A snapshot field's metadata with its description: the state document's OpenAPI
    schema shows ``text`` (its whitespace runs made single spaces) for the field.
    ``more``: :data:`OMIT` or :data:`INLINE` as well."""
    merged = {"description": " ".join(text.split())}
    for extra in more:
        merged.update(extra)
    return MappingProxyType(merged)


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

    obstacle: str = field(
        metadata=described("The obstacle's name (for a self-collision: the other link).")
    )
    link: str = field(metadata=described("The robot link that touches it."))
    group: str = field(metadata=described("The link's control group."))
    depth_mm: float = field(
        metadata=described("How far the link's shape overlaps the obstacle (mm).")
    )
    self_collision: bool = False


def _no_obstacles() -> tuple[Obstacle, ...]:
    return ()


@dataclass(frozen=True, slots=True)
class WorkspaceSnapshot:
    """The cell's obstacles now and what the robot touches (issue 21)."""

    obstacles: tuple[Obstacle, ...] = field(
        default_factory=_no_obstacles,
        metadata=described(
            """Each obstacle in the cell file's keys: name, one of box/cylinder/sphere, xyz
            (m), rpy_deg, and frame when it is given in another group's frame."""
        ),
    )
    contacts: tuple[ContactInfo, ...] = field(
        default=(), metadata=described("What the robot touches now (empty: nothing).")
    )


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
    queue: int = field(metadata=described("Increments queued for the group."))
    tool: int
    tcp: TcpSnapshot | None = field(
        default=None,
        metadata=described("The active tool's TCP (null: the group has no kinematic chain)."),
    )


# ------------------------------------------------------------------- the safety unit's part


@dataclass(frozen=True, slots=True)
class FsuLimits:
    """The active limits (None: that limit is off)."""

    joint_speed_pct: int | None
    tcp_speed_mm_s: float | None


PflPhase = Literal["off", "idle", "stop", "escape"]
"""The PFL function as the operator sees it ("off": no PFL in this cell)."""

_NO_FSU_LIMITS: Final = FsuLimits(None, None)


@dataclass(frozen=True, slots=True)
class SafetySnapshot:
    """What the safety functions show the operator, one field each: the controller's
    snapshot carries it and the state document lists its fields at its top level
    (``"fsu"``, ``"pfl"``). A new function adds its field here, described
    (:func:`described`: the OpenAPI schema's description), and fills it in
    :meth:`~pymotoros.controller.safety.SafetyUnit.snapshot`."""

    fsu: FsuLimits = field(
        default=_NO_FSU_LIMITS,
        metadata=described("The FSU speed limits in force (null: that limit is off)."),
    )
    pfl: PflPhase = field(
        default="off",
        metadata=described(
            """The PFL function: off (not in this cell), idle, stop (81702 on) or escape
            (81703 on, retreating after a clamping)."""
        ),
    )


# ------------------------------------------------------------------- the operator's part


@dataclass(frozen=True, slots=True)
class OperatorSnapshot:
    """What the pendant's keys show the operator, one field each: the controller's
    snapshot carries it and the state document lists its fields at its top level
    (``"mode"`` … ``"alarms"``). A new key with state of its own adds its field here,
    described (:func:`described`: the OpenAPI schema's description), and fills it in
    :meth:`~pymotoros.controller.operator_keys.OperatorKeys.snapshot`."""

    mode: PendantMode = field(metadata=described("The pendant's mode switch."))
    remote: bool = field(
        metadata=described("Remote mode: play commands come from outside (MotoROS needs it).")
    )
    servo: bool = field(metadata=described("Servo power is on."))
    estop: bool = field(
        metadata=described("An E-stop is pressed (pendant, external or the cell's).")
    )
    hold: bool = field(metadata=described("The hold key (or the external hold input) is on."))
    alarms: tuple[AlarmInfo, ...] = field(
        metadata=described("Active alarms: code, subcode and text.")
    )
    errors: tuple[AlarmInfo, ...] = field(default=(), metadata=OMIT)
    """Active operator errors (the pendant's extras)."""
    eco: bool | None = field(default=None, metadata=OMIT)
    """Eco mode: servo power saved while idle (the pendant's extras; None: not modelled)."""


# ------------------------------------------------------------------------------ the cell

SERVO_ON_DELAY_MS: Final = 500
"""Time from a servo-on request to 50073 (brakes released, amplifiers ready). Yaskawa
publishes no figure; about half a second is what an operator sees on the pendant
(modelling choice, docs/fidelity.md)."""
FEEDBACK_LAG_TICKS: Final = 3
"""Mean delay of the encoder feedback behind the command, in ticks (12 ms at 4 ms)."""


@dataclass(frozen=True, slots=True)
class StartupConfig:
    """The controller facts the start-up checks read (cell file ``[controller]``)."""

    software: str | None = None
    """System software version, e.g. "YAS2.80.00-00" (None: a version that passes)."""
    conveyor_tracking: bool = False
    parameters: Mapping[str, int] = field(default_factory=dict)
    """Set-up parameters that differ from
    :data:`~pymotoros.controller.safety.startup.PASSING_PARAMETERS`."""
    validation_code: int | None = None
    """A validation code no modelled setting produces: 9 ("MotoROS not compatible with
    HC"), 10 or > 11 ("Controller config invalid", e.g. 102..106 for licensing)."""


@dataclass(frozen=True, slots=True)
class PeripheralConfig:
    """One ``[[peripherals]]`` table of the cell file."""

    name: str
    input: int
    """The bit the device drives (e.g. a universal input, 20010)."""
    follows: int
    """The bit it reacts to (e.g. a universal output, 10010)."""
    delay_ms: int = 0
    invert: bool = False


@dataclass(frozen=True, slots=True)
class ToolConfig:
    """A tool file: number 0..63, with the data the PFL function relies on."""

    number: int
    name: str = ""
    mass_kg: float = 0.0
    tcp_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """The TCP's orientation on tool0: fixed-axis roll, pitch, yaw (R = Rz·Ry·Rx)."""
    shape: ToolShape | None = None
    """Its collision shape on the flange (None: a capsule from the flange to the TCP)."""

    @property
    def cell_tool(self) -> CellTool:
        """The tool as the client and the collision model read it (TCP and shape)."""
        return CellTool(self.number, self.name, Transform(self.tcp_m, self.rpy_rad), self.shape)


@dataclass(frozen=True, slots=True)
class InitialState:
    """The controller at boot. Default: PLAY, REMOTE, servo off, nothing pressed or active."""

    mode: PendantMode = PendantMode.PLAY
    remote: bool = True
    servo: bool = False
    estop: bool = False
    hold: bool = False
    eco: bool = False
    alarms: tuple[AlarmInfo, ...] = ()
    joints: tuple[tuple[float, ...], ...] = ()
    """Per group, ROS order (rad, m); empty → every joint at 0."""
    tools: tuple[int, ...] = ()
    """Per group, the selected tool; empty → tool 0 (as after a reboot, §5.8)."""


@dataclass(frozen=True, slots=True)
class ServoConfig:
    servo_on_delay_ms: int = SERVO_ON_DELAY_MS
    lag_ticks: int = FEEDBACK_LAG_TICKS
    noise_pulses: int = 0
    brake_sag_pulses: int = 0
    """When servo power goes off (servo off, E-stop, eco mode) the brakes hold the axes
    a little away from where they were: each axis moves by a seeded amount within
    ±this many pulses, command and feedback alike (0: no sag)."""
    eco_idle_s: int | None = None
    """Eco mode starts after this many seconds with servo on and no motion (None: never)."""
    fsu_speed_limit_pct: int | None = None
    """A Functional Safety Unit joint-speed limit: the controller executes at most this
    share of each axis's maximum increment per tick and drops the rest (None: no FSU)."""


@dataclass(frozen=True, slots=True)
class CellConfig:
    """Everything :class:`~pymotoros.controller.VirtualController` needs to boot."""

    controller: ControllerModel
    groups: tuple[GroupModel, ...]
    robots: tuple[str, ...]
    """Robot model name of each group."""
    name: str = "cell"
    tools: tuple[ToolConfig, ...] = ()
    initial: InitialState = field(default_factory=InitialState)
    group_tools: tuple[tuple[ToolConfig, ...], ...] = ()
    """Per group, the tool files of ``[[groups.tools]]`` (empty: none beyond ``[[tools]]``)."""
    s1cxg: tuple[S1cxgTable | None, ...] = ()
    """Per group, the S1CxG register output parameters of ``[groups.s1cxg]`` (empty or
    None: no register outputs, the default)."""
    servo: ServoConfig = field(default_factory=ServoConfig)
    pfl: bool = False
    """The PFL option is enabled (HC robots on YRC1000 / YRC1000micro)."""
    jobs: str | tuple[Path, ...] = "auto"
    """A built-in INIT_ROS variant name, "auto", or job files/directories."""
    warnings: tuple[str, ...] = ()
    source: str = "<default cell>"
    startup: StartupConfig = field(default_factory=StartupConfig)
    """What MotoROS's start-up checks read: software version, conveyor tracking, set-up
    parameters (``[controller]``, ``[controller.parameters]``)."""
    peripherals: tuple[PeripheralConfig, ...] = ()
    """``[[peripherals]]``: inputs that follow other bits like devices (docs/cell.md)."""
    model_groups: tuple[str, ...] = ()
    """Each group's name in its robot model (empty: the group's own name), see
    :attr:`pymotoros.models.cell.CellModels.model_groups`."""
    workspace: Workspace = EMPTY_WORKSPACE
    """``[workspace]``: obstacles the robot may touch (docs/workspace.md)."""
    fidelity: Fidelity = DEFAULT_FIDELITY
    """``[motoros] fidelity``: exact (MotoROS 1.9.12's surprises kept, the default) or
    safe (the twin's kinder behaviour); docs/fidelity.md §1."""

    def tool(self, group_index: int, number: int) -> ToolConfig:
        """Tool file ``number`` of a group: its own ``[[groups.tools]]`` entry, else the
        cell-wide ``[[tools]]`` one, else an empty tool (all zero, as an unset tool file)."""
        own = self.group_tools[group_index] if group_index < len(self.group_tools) else ()
        for t in (*own, *self.tools):
            if t.number == number:
                return t
        return ToolConfig(number)

    def as_table(self) -> dict[str, Any]:
        """Its name, controller and groups in the cell file's shape (JSON-able): what
        ``pymotoros sim --ports-file`` tells the robot commands about the cell."""
        names = self.model_groups or tuple(g.name for g in self.groups)
        return cell_table(self.name, self.controller.type.value, self.robots, names)

    @property
    def job_variant(self) -> str | None:
        """The built-in job set to load (None when the cell names job files)."""
        if isinstance(self.jobs, tuple):
            return None
        if self.jobs != "auto":
            return self.jobs
        multi = len(self.groups) > 1
        if self.controller.skillsnd:
            return "dx100_multi_group" if multi else "dx100_single_arm"
        return "multi_group" if multi else "single_arm"


# ------------------------------------------------------------------------- scenarios


class EventAction(Protocol):
    """What a scenario event carries out: an action's declaration
    (:class:`~pymotoros.controller.actions.ActionSpec`), as the scenario needs it."""

    @property
    def name(self) -> str: ...

    def perform(self, target: Any, params: Mapping[str, Any]) -> None:
        """Run the action on ``target`` with checked parameters."""
        ...


@dataclass(frozen=True, slots=True)
class ScenarioEvent:
    """One event: a trigger and an action with its parameters."""

    index: int
    trigger: str
    """"at", "after_motion" or "when_io"."""
    seconds: float = 0.0
    """For "at" and "after_motion"."""
    io: tuple[int, int] = (0, 0)
    """(address, value) for "when_io"."""
    action: str = ""
    params: Mapping[str, object] = field(default_factory=dict)
    """The parameters as given (the optional ones left out keep their default)."""
    spec: EventAction | None = None
    """The action's declaration (None: looked up by name among the declared actions)."""


@dataclass(frozen=True, slots=True)
class Scenario:
    """A fault scenario: the events a twin plays on its own clock (``pymotoros sim
    --scenario FILE``); ``source`` names the file in error messages."""

    events: tuple[ScenarioEvent, ...]
    source: str = "<scenario>"


# -------------------------------------------------------------------------- the snapshot


def _no_safety() -> SafetySnapshot:
    return SafetySnapshot()


# Not slotted: on Python 3.11 a frozen slotted dataclass answers an assignment to one of
# its properties (``snapshot.hold = False``) with a TypeError from its generated
# ``__setattr__``; unslotted, it is the FrozenInstanceError that names the attribute.
@dataclass(frozen=True)
class ControllerSnapshot:
    """An immutable picture of the controller for observers (HTTP API, pendant, tests).

    This is the one declaration of the state document: ``GET /api/state``, the
    ``/ws/state`` feed, the pendant and the control API's OpenAPI schema are derived from
    these fields, their types and their descriptions (:func:`described`, in each
    field's metadata; :mod:`pymotoros.runtime.snapshot_document`). A new field appears
    in all of them with no other edit; metadata :data:`OMIT` keeps one out of the
    document, :data:`INLINE` merges a part's fields into it. Two parts fill their own
    state: the pendant's keys (:attr:`operator`, whose fields ``mode`` … ``alarms`` are
    the document's first keys and readable here as properties) and the safety unit
    (:attr:`safety`).
    """

    time_ms: int = field(metadata=OMIT)
    tick_count: int = field(metadata=OMIT)
    operator: OperatorSnapshot = field(
        metadata=described(
            "The operator state the pendant's keys show (``controller/operator_keys.py``).",
            INLINE,
        )
    )
    motion_ready: bool = field(
        metadata=described(
            """Motion-ready as of the current signals: what CHECK_MOTION_READY answers
            once MotoROS's 10 ms status monitor has seen them (never a reading from
            before the latest operator action)."""
        )
    )
    groups: tuple[GroupSnapshot, ...] = field(
        metadata=described("Every control group, in group order.")
    )
    safety: SafetySnapshot = field(
        default_factory=_no_safety,
        metadata=described(
            "What the cell's safety functions show (``controller/safety``): one key each.",
            INLINE,
        ),
    )
    events: tuple[FiredEventInfo, ...] = field(
        default=(),
        metadata=described(
            """Scenario events fired: {"t": seconds since boot, "action": ..., its
            parameters, "error" when the controller refused it}."""
        ),
    )
    motoros: str = field(
        default="running",
        metadata=described(
            """MotoROS's start-up: "running", what it waits for, or why it halted (§2.1,
            §8)."""
        ),
    )
    workspace: WorkspaceSnapshot = field(
        default_factory=WorkspaceSnapshot,
        metadata=described(
            "The cell's obstacles (as put and removed at run time) and the contacts now."
        ),
    )
    # What a pendant shows beyond the control API's document (its ``pendant`` extras);
    # None where a controller (a test double) does not model it.
    period_ms: int | None = field(default=None, metadata=OMIT)
    """The interpolation period (ms)."""
    not_ready: NotReadyInfo | None = field(default=None, metadata=OMIT)
    """Why motion is not ready now (subcode 0 when it is)."""
    jobs: tuple[JobPosition, ...] | None = field(default=None, metadata=OMIT)
    """The line of every running job task (empty when no job runs)."""
    motoros_outputs: tuple[int, ...] | None = field(default=None, metadata=OMIT)
    """OT#889..896 (:data:`MOTOROS_FIRST_OUTPUT` on), 0 or 1 each."""
    cell: CellConfig | None = field(default=None, metadata=OMIT)
    """The cell the controller was built from (models, tools, groups): fixed at boot."""

    @property
    def pfl(self) -> PflPhase:
        """The PFL function: "off", "idle", "stop" or "escape"."""
        return self.safety.pfl

    # The operator part's fields, read as they were before the keys filled their own part.
    @property
    def mode(self) -> PendantMode:
        """The pendant's mode switch."""
        return self.operator.mode

    @property
    def remote(self) -> bool:
        """Remote mode: play commands come from outside (MotoROS needs it)."""
        return self.operator.remote

    @property
    def servo(self) -> bool:
        """Servo power is on."""
        return self.operator.servo

    @property
    def estop(self) -> bool:
        """An E-stop is pressed (pendant, external or the cell's)."""
        return self.operator.estop

    @property
    def hold(self) -> bool:
        """The hold key (or the external hold input) is on."""
        return self.operator.hold

    @property
    def alarms(self) -> tuple[AlarmInfo, ...]:
        """Active alarms: code, subcode and text."""
        return self.operator.alarms

    @property
    def errors(self) -> tuple[AlarmInfo, ...]:
        """Active operator errors (not alarms): code, subcode and text."""
        return self.operator.errors

    @property
    def eco(self) -> bool | None:
        """Eco mode: servo power saved while idle (None: not modelled)."""
        return self.operator.eco
