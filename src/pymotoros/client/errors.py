"""Typed errors of the client: what the robot said, the numbers behind it, and what to do.

::

    PymotorosError
     +-- ClientError
          +-- ConnectError              (ConnectionError) a port could not be opened
          +-- ConnectionLostError       (ConnectionError) the peer closed or the socket broke
          |    +-- StateStreamLostError  the state stream stalled or closed during a move:
          |                              streaming stopped, STOP_MOTION sent, what was lost
          +-- RequestTimeoutError       (TimeoutError) no reply / no state within the timeout
          +-- MotionTimeoutError        (TimeoutError) the robot did not finish a move in time
          +-- MotionIncompleteError     the robot came to rest away from the goal
          +-- MoveStoppedError          stop() ended the move (STOP_MOTION sent)
          +-- MoveInProgressError       a second move while one runs: refused at once
          +-- ReplyError                the controller refused a request (.result, .subcode)
          |    +-- NotReadyError        result 5 (or FALSE to CHECK_MOTION_READY), .reason
          |    +-- InvalidRequestError  result 3
          |    |    +-- StartPositionError  3011, per-axis deviation in pulses and rad
          |    |    +-- SpeedLimitError     3013, per-axis velocity against the limit
          |    +-- CommandFailedError   result 2 (FAILURE)
          |    +-- BusyTimeoutError     result 1 for longer than the BUSY budget (TimeoutError)
          +-- IoError                   an IO reply with a non-zero result code (.result_code)
               +-- IoAddressError       refused before sending (ValueError): address out of range

One table, :data:`REPLY_ERRORS`, maps every ``(result, subcode)`` MotoROS 1.9.12 can
send to the class raised and a remedy sentence; :func:`reply_error` builds the
exception. Codes and their meanings come from ``pymotoros.protocol.constants``
(reference §1.7, §4.2).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final

from pymotoros.errors import PymotorosError
from pymotoros.models.rules import START_TOLERANCE_PULSES
from pymotoros.protocol.constants import (
    MAX_TOOL_NUMBER,
    InvalidSubcode,
    IoResultCode,
    MotionCommand,
    MsgType,
    NotReadySubcode,
    ResultCode,
    reply_result,
    subcode_meaning,
)


class ClientError(PymotorosError):
    """Root of the errors the client raises."""

    early_stop: EarlyStop | None = None
    """Set when this error ended a move and the library then stopped the robot
    (STOP_MOTION): whether the stop worked, where the robot came to rest (``positions``,
    rad/m of the moved groups) and the sentence already appended to the message. A caller
    that words its own message (the CLI) adds only what is new, not the position again."""


@dataclass(frozen=True, slots=True)
class EarlyStop:
    """How a move that ended early was stopped
    (:meth:`~pymotoros.client.streaming.TrajectoryStreamer.stop_early`)."""

    stopped: bool
    """STOP_MOTION was acknowledged (SUCCESS)."""
    at_rest: bool
    """The feedback then showed the robot at rest."""
    positions: tuple[float, ...]
    """Where the robot stands (or was last reported), joints of the moved groups."""
    took_s: float
    """From the stop's start to rest (or to giving up)."""
    why: str
    """What ended the move."""
    detail: str
    """Where the robot stopped, with units, or why it may not have."""

    @property
    def text(self) -> str:
        return f"{self.why}: {self.detail}"

    def tell(self, exc: BaseException) -> None:
        """Put the stop into ``exc``: the client's own errors get it in their message
        (what the CLI prints), anything else (``CancelledError``, ``KeyboardInterrupt``,
        the caller's exception) a note, so its type and message stay as they were."""
        if isinstance(exc, ClientError) and exc.args and isinstance(exc.args[0], str):
            exc.args = (f"{exc.args[0]}; {self.detail}", *exc.args[1:])
            exc.early_stop = self
        else:
            exc.add_note(self.text)


class ConnectError(ClientError, ConnectionError):
    """A TCP connection to the controller could not be opened."""

    def __init__(self, message: str, *, host: str, port: int) -> None:
        super().__init__(message)
        self.host = host
        self.port = port


class ConnectionLostError(ClientError, ConnectionError):
    """The connection closed while the client was using it; every waiter gets this at once."""


SECOND_MOTION_CLIENT: Final = (
    "closed by the controller before it answered anything: MotoROS takes one motion "
    "connection, and while the robot moves (increments queued) it closes a new one at once "
    "(reference §2.2): another client holds the motion connection and is moving the "
    "robot. Wait until its move has ended, or stop it there (Ctrl-C in its terminal, HOLD "
    "on the pendant), then connect again"
)
"""Why a motion connection closes before its first reply (the one-motion-client rule)."""

REPLACED_MOTION_CLIENT: Final = (
    "closed by the controller (MotoROS takes one motion connection: a client that connects "
    "to the motion port while no motion is queued takes it over and the older connection "
    "is closed, reference §2.2; was another client started?)"
)
"""Why an established motion connection may close (it was taken over)."""


class StateStreamLostError(ConnectionLostError):
    """The state stream stalled (or closed) while a trajectory was streamed or followed.

    Streaming more points blind would move a robot nobody watches, so the client stops
    sending, asks for STOP_MOTION on the motion port (which may still answer) and raises
    this, saying what it knows: the last position the stream reported, how many points
    the robot had accepted, and whether the stop was acknowledged. Exit code 3 in the CLI.
    """

    def __init__(
        self,
        message: str,
        *,
        silent_s: float | None,
        positions: tuple[float, ...],
        accepted_points: int,
        total_points: int,
        stopped: bool,
    ) -> None:
        super().__init__(message)
        self.silent_s = silent_s
        """How long the stream had been silent (None: it closed instead)."""
        self.positions = positions
        """The last position the state stream reported (joints of the moved groups)."""
        self.accepted_points = accepted_points
        """Points the controller accepted (SUCCESS) before streaming stopped."""
        self.total_points = total_points
        self.stopped = stopped
        """True when STOP_MOTION was answered with SUCCESS."""


class MotionConnectionLostError(ConnectionLostError):
    """The motion connection closed while a trajectory was streamed or followed.

    MotoROS goes on with the points it had queued after its motion connection closed
    (reference §2.2) and STOP_MOTION cannot be sent without it: the message says so, asks
    to stop the robot on the pendant, and gives the last position the state stream
    reported. Exit code 3 in the CLI, as every lost connection.
    """

    def __init__(
        self,
        message: str,
        *,
        positions: tuple[float, ...],
        accepted_points: int,
        total_points: int,
    ) -> None:
        super().__init__(message)
        self.positions = positions
        """The last position the state stream reported (joints of the moved groups)."""
        self.accepted_points = accepted_points
        """Points the controller accepted (SUCCESS): they may still run."""
        self.total_points = total_points


class RequestTimeoutError(ClientError, TimeoutError):
    """No reply (or no state message) arrived within the timeout."""


class MotionTimeoutError(ClientError, TimeoutError):
    """A move did not finish (queue empty, at rest, at the goal) within its time budget."""


class MotionIncompleteError(ClientError):
    """The robot stopped moving before it reached the goal (and nothing says why)."""


class GroupError(ClientError, ValueError):
    """A control group that the robot model (or cell) given to the client does not have."""


class ModelMismatchError(ClientError):
    """The controller streams other groups or more axes than the robot model given to the client.

    Named as such because it otherwise looks like a connection problem (a wait for
    feedback of a group that never comes).
    """


class MoveStoppedError(ClientError):
    """A move ended early because :meth:`RobotClient.stop` was called (STOP_MOTION sent)."""

    def __init__(self, message: str, *, positions: tuple[float, ...] = ()) -> None:
        super().__init__(message)
        self.positions = positions


class MoveInProgressError(ClientError):
    """A move was asked for while another move of the same client still runs.

    MotoROS executes one trajectory at a time; the second is refused before anything is
    sent, and the message says how to wait for the first or stop it.
    """


@dataclass(frozen=True, slots=True)
class AxisDeviation:
    """How far one axis of a refused point is from what the controller accepts."""

    axis: int
    """Index in ROS order (0-based)."""
    name: str
    value: float
    """The requested position (rad/m) or velocity (rad/s, m/s)."""
    reference: float
    """The commanded position (for 3011) or the speed limit (for 3013), same unit."""
    pulses: int | None = None
    """For 3011: |requested − commanded| in pulses, as MotoROS measures it."""

    @property
    def difference(self) -> float:
        """``value - reference``: how far past the limit or tolerance the point was (same unit)."""
        return self.value - self.reference


class ReplyError(ClientError):
    """The controller answered a request with something other than SUCCESS."""

    def __init__(
        self,
        message: str,
        *,
        result: int,
        subcode: int,
        command: int,
        remedy: str,
        point: int | None = None,
    ) -> None:
        super().__init__(message)
        self.result = result
        self.subcode = subcode
        self.command = command
        """The echoed command code (MOTO_MOTION_CTRL) or message type (14, 2016, 2018)."""
        self.meaning = describe_reply(result, subcode)
        self.remedy = remedy
        self.point = point
        """Index of the trajectory point that was refused, when a point was refused."""


class NotReadyError(ReplyError):
    """The controller is not ready for motion; :attr:`reason` says why."""

    @property
    def reason(self) -> NotReadySubcode | None:
        """The NOT_READY subcode as an enum (what to fix: servo off, E-stop ...); None for a code
        this version does not know."""
        try:
            return NotReadySubcode(self.subcode)
        except ValueError:
            return None


class InvalidRequestError(ReplyError):
    """The controller refused the request or its data (result INVALID)."""


class StartPositionError(InvalidRequestError):
    """3011: the first point is beyond the start tolerance from the commanded position.

    :attr:`deviations` lists every axis beyond the tolerance (pulses and rad);
    the client computes them from the robot model and the latest feedback.
    """

    def __init__(
        self, message: str, *, deviations: Sequence[AxisDeviation] = (), **kwargs: object
    ) -> None:
        super().__init__(message, **kwargs)  # type: ignore[arg-type]
        self.deviations = tuple(deviations)
        self.tolerance_pulses = START_TOLERANCE_PULSES


class SpeedLimitError(InvalidRequestError):
    """3013: a point's velocity is above an axis's maximum; :attr:`deviations` says which."""

    def __init__(
        self, message: str, *, deviations: Sequence[AxisDeviation] = (), **kwargs: object
    ) -> None:
        super().__init__(message, **kwargs)  # type: ignore[arg-type]
        self.deviations = tuple(deviations)


class CommandFailedError(ReplyError):
    """The controller tried and failed (result FAILURE)."""


class BusyTimeoutError(ReplyError, TimeoutError):
    """The controller kept answering BUSY for longer than the retry budget."""


class IoError(ClientError):
    """An IO or M-register request came back with a non-zero result code."""

    def __init__(self, message: str, *, address: int, result_code: int, remedy: str) -> None:
        super().__init__(message)
        self.address = address
        self.result_code = result_code
        self.remedy = remedy


class IoAddressError(IoError, ValueError):
    """An IO address or value the controller would refuse; raised before anything is sent."""


# --------------------------------------------------------------------------- the table

NOT_READY_REMEDIES: Final[Mapping[NotReadySubcode, str]] = MappingProxyType(
    {sub: sub.remedy for sub in NotReadySubcode}
)
"""Each NOT_READY reason's remedy, as the reason declares it (``NotReadySubcode.remedy``,
the one text every surface shows)."""

INVALID_REMEDIES: Final[Mapping[InvalidSubcode, str]] = {
    InvalidSubcode.UNSPECIFIED: "report this: MotoROS 1.9.12 never sends it",
    InvalidSubcode.MSGSIZE: (
        "the controller read a short message: check --controller (byte order) and that "
        "nothing else talks on this port"
    ),
    InvalidSubcode.MSGHEADER: "report this: MotoROS 1.9.12 never sends it",
    InvalidSubcode.MSGTYPE: (
        "this MotoROS does not know the message: M-registers need the IO port and "
        "MotoROS ≥ 1.9.2, tools ≥ 1.9.0; update MotoROS"
    ),
    InvalidSubcode.GROUPNO: "the group number does not exist on this controller: check --robot",
    InvalidSubcode.SEQUENCE: "sequence numbers must be 0 or positive",
    InvalidSubcode.COMMAND: "the motion command is unknown to MotoROS",
    InvalidSubcode.DATA: "report this: MotoROS 1.9.12 never sends it",
    InvalidSubcode.DATA_START_POS: (
        "start the trajectory where the robot is: wait until it is at rest and use its "
        "settled position as point 0 (move_joints does this); after eco mode or a stop, "
        "read the position again"
    ),
    InvalidSubcode.DATA_POSITION: "report this: MotoROS 1.9.12 never sends it",
    InvalidSubcode.DATA_SPEED: (
        "slow the trajectory down (lower speed scaling) or re-plan with the robot's "
        "velocity limits; check that --robot matches the arm"
    ),
    InvalidSubcode.DATA_ACCEL: "report this: MotoROS 1.9.12 never sends it",
    InvalidSubcode.DATA_INSUFFICIENT: "every point needs time, positions and velocities",
    InvalidSubcode.DATA_TIME: "point times must stay below 4 hours (14400 s): split the motion",
    InvalidSubcode.DATA_TOOLNO: f"tool numbers are 0..{MAX_TOOL_NUMBER}",
}

FAILURE_REMEDIES: Final[Mapping[int, str]] = {
    MotionCommand.CHECK_QUEUE_CNT: "the group number does not exist: check --robot",
    MotionCommand.STOP_MOTION: (
        "the queues were cleared but the interpolator did not go idle in 20 ms: send stop again"
    ),
    MotionCommand.START_SERVOS: (
        "servo power did not come on within 5 s: check E-stop, safety fence and the pendant"
    ),
    MotionCommand.STOP_SERVOS: "servo power did not go off within 5 s: check the pendant",
    MotionCommand.RESET_ALARM: "the alarm could not be reset: remove its cause first",
    MotionCommand.STOP_TRAJ_MODE: (
        "motion is still queued: wait until the robot stops, or stop it (stop_motion()), "
        "then disable again"
    ),
    MotionCommand.DISCONNECT: "motion is still queued: stop it first, then disconnect",
}

_DEFAULT_FAILURE_REMEDY: Final = "look at the pendant for the reason and try again"

BUSY_REMEDY: Final = (
    "the controller kept its point buffer full: check that the robot is moving (HOLD, "
    "a safety speed limit), or allow a longer busy_timeout_s"
)


def describe_reply(result: int, subcode: int) -> str:
    """``NAME (code): meaning`` of a reply's subcode (or result, when the subcode is 0).

    CHECK_MOTION_READY answers FALSE with a NOT_READY subcode; it is described as one.
    """
    return subcode_meaning(reply_result(result, subcode), subcode)


def _error_class(result: int, subcode: int) -> type[ReplyError]:
    if result == ResultCode.NOT_READY:
        return NotReadyError
    if result == ResultCode.INVALID:
        if subcode == InvalidSubcode.DATA_START_POS:
            return StartPositionError
        if subcode == InvalidSubcode.DATA_SPEED:
            return SpeedLimitError
        return InvalidRequestError
    if result == ResultCode.BUSY:
        return BusyTimeoutError
    return CommandFailedError


def remedy_for(result: int, subcode: int, command: int) -> str:
    """The remedy sentence for a refusal."""
    if reply_result(result, subcode) == ResultCode.NOT_READY:
        try:
            return NOT_READY_REMEDIES[NotReadySubcode(subcode)]
        except ValueError:
            return NOT_READY_REMEDIES[NotReadySubcode.UNSPECIFIED]
    if result == ResultCode.INVALID:
        try:
            return INVALID_REMEDIES[InvalidSubcode(subcode)]
        except ValueError:
            return _DEFAULT_FAILURE_REMEDY
    if result == ResultCode.BUSY:
        return BUSY_REMEDY
    return FAILURE_REMEDIES.get(command, _DEFAULT_FAILURE_REMEDY)


def describe_command(command: int) -> str:
    """``START_TRAJ_MODE`` for a motion command, ``message 14`` for a message type."""
    try:
        return MotionCommand(command).name
    except ValueError:
        pass
    try:
        return MsgType(command).name
    except ValueError:
        return f"message type {command}"


def reply_error(
    result: int,
    subcode: int,
    command: int,
    *,
    point: int | None = None,
    detail: str = "",
    deviations: Sequence[AxisDeviation] = (),
) -> ReplyError:
    """Build the typed exception for a refused request (the one mapping of the client)."""
    # CHECK_MOTION_READY answers FALSE with a NOT_READY subcode: the same cause as result 5.
    effective = reply_result(result, subcode)
    cls = _error_class(effective, subcode)
    remedy = remedy_for(effective, subcode, command)
    where = describe_command(command) if point is None else f"point {point}"
    text = f"{where} refused: {describe_reply(effective, subcode)}"
    if detail:
        text += f" ({detail})"
    text += f". What to do: {remedy}"
    kwargs: dict[str, object] = {
        "result": result,
        "subcode": subcode,
        "command": command,
        "remedy": remedy,
        "point": point,
    }
    if cls in (StartPositionError, SpeedLimitError):
        kwargs["deviations"] = deviations
    return cls(text, **kwargs)  # type: ignore[arg-type]


IO_REMEDIES: Final[Mapping[IoResultCode, str]] = {
    IoResultCode.READ_ADDRESS_INVALID: (
        "the address is not readable on this controller: check the IO map of --controller"
    ),
    IoResultCode.WRITE_ADDRESS_INVALID: (
        "MotoROS writes only general outputs, network inputs, the interface panel and M000-M559"
    ),
    IoResultCode.WRITE_VALUE_INVALID: "bits take 0 or 1, groups 0..255, M-registers 0..65535",
    IoResultCode.READ_API_ERROR: "the controller could not read the signal: check the pendant",
    IoResultCode.WRITE_API_ERROR: "the controller could not write the signal: check the pendant",
}


def io_error(result_code: int, address: int, what: str) -> IoError:
    """The typed exception for an IO reply whose result code is not OK."""
    try:
        code = IoResultCode(result_code)
        meaning, remedy = code.meaning, IO_REMEDIES.get(code, _DEFAULT_FAILURE_REMEDY)
    except ValueError:
        meaning, remedy = f"unknown result code {result_code}", _DEFAULT_FAILURE_REMEDY
    return IoError(
        f"{what} {address} refused: {result_code} {meaning}. What to do: {remedy}",
        address=address,
        result_code=result_code,
        remedy=remedy,
    )
