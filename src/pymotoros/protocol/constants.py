"""Every code that travels on the wire, and the protocol's fixed sizes.

This is the leaf module of the package: the controller, the motion engine, the
servers and the client all speak this vocabulary. Names follow MotoROS's
``SimpleMessage.h`` with the C prefix (``ROS_MSG_``, ``ROS_RESULT_`` …) dropped,
so the C header and these enums can be compared line by line. Values and
meanings come from our behavioural notes on MotoROS 1.9.12
(``shared/reference/motoros-1.9.12.md``, §1.2, §1.3 and §1.7).

Every member carries a one-line human meaning in ``.meaning``; error messages
and logs use it so that nobody has to look up what 5006 means.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from typing import Final, Self


class _Described(enum.IntEnum):
    """An ``IntEnum`` whose members carry a short human meaning.

    Declared as ``NAME = value, "meaning"``.
    """

    meaning: str

    def __new__(cls, value: int, meaning: str = "") -> Self:
        member = int.__new__(cls, value)
        member._value_ = value
        member.meaning = meaning
        return member

    @classmethod
    def describe(cls, value: int) -> str:
        """``"NAME (value): meaning"`` for a known value, a clear text for an unknown one."""
        try:
            member = cls(value)
        except ValueError:
            return f"unknown {cls.__name__} value {value}"
        return f"{member.name} ({int(member)}): {member.meaning}"


# --------------------------------------------------------------------------- sizes

MAX_JOINTS: Final = 10
"""ROS_MAX_JOINT: joint slots in every position/velocity/acceleration array on the wire."""

MAX_PULSE_AXES: Final = 8
"""MP_GRP_AXES_NUM: axes a controller group can have; slots 8 and 9 are never used (§1.4)."""

MAX_GROUPS: Final = 4
"""MOT_MAX_GR: group slots in JOINT_TRAJ_PT_FULL_EX / JOINT_FEEDBACK_EX and the DH reply."""

MAX_DH_LINKS: Final = 8
"""Links per group in the GET_DH_PARAMETERS reply (4 groups × 8 links × 4 floats = 512 bytes)."""

PREFIX_SIZE: Final = 4
"""The int32 length prefix; its value counts the bytes after it (header + body)."""

HEADER_SIZE: Final = 12
"""msg_type, comm_type, reply_type: three int32."""

MAX_MESSAGE_SIZE: Final = 552
"""Largest struct MotoROS receives: prefix + header + 4-group JOINT_TRAJ_PT_FULL_EX (§1.1)."""

MAX_WIRE_MESSAGE_SIZE: Final = 552
"""Largest message either side sends: also 552 (the DH reply is 528, FEEDBACK_EX 548)."""

MAX_LENGTH_PREFIX: Final = MAX_WIRE_MESSAGE_SIZE - PREFIX_SIZE
"""Largest sane value of the length prefix (548)."""

INT32_MIN: Final = -(2**31)
"""Smallest value of a signed 32-bit wire field (every integer field but the IO values)."""

INT32_MAX: Final = 2**31 - 1
"""Largest value of a signed 32-bit wire field; also the bound of C's int conversions."""

UINT32_MAX: Final = 2**32 - 1
"""Largest value of an unsigned 32-bit wire field (IO and M-register values, §1.6)."""

MAX_TOOL_NUMBER: Final = 63
"""Highest tool file number: tools 0..63, anything else is refused with 3017 (§5.8)."""

# --------------------------------------------------------------------------- byte order and ports


class ByteOrder(enum.StrEnum):
    """Wire byte order; the value is the ``struct`` prefix.

    MotoROS never swaps bytes: little-endian on DX100, DX200, YRC1000 and
    YRC1000micro (x86), big-endian on FS100 (PowerPC) (§1.1).
    """

    LITTLE = "<"
    BIG = ">"


class Port(enum.Enum):
    """Which MotoROS server a message travels on; decoding of a few types depends on it.

    Type 2002 is a MOTO_MOTION_REPLY on the motion port but the IO error reply
    (result at body offset 0) on the IO port (§1.6).
    """

    MOTION = "motion"
    STATE = "state"
    IO = "io"


TCP_PORT_MOTION: Final = 50240
"""Motion server: one client (MotoROS Controller.h)."""

TCP_PORT_STATE: Final = 50241
"""State server: up to four clients."""

TCP_PORT_IO: Final = 50242
"""IO server: one client (since MotoROS 1.6.0)."""

STANDARD_PORTS: Final[Mapping[int, Port]] = {
    TCP_PORT_MOTION: Port.MOTION,
    TCP_PORT_STATE: Port.STATE,
    TCP_PORT_IO: Port.IO,
}
"""The MotoROS port numbers (reference §1.1): a connection to one of them is that port."""


# --------------------------------------------------------------------------- header codes


@enum.unique
class MsgType(_Described):
    """Message types MotoROS 1.9.12 defines (§1.3). 2014, 2015 and 2019 do not exist."""

    PING = 1, "ping; answered with an empty PING reply"
    GET_VERSION = 2, "version request; defined but never handled (answered INVALID/3003)"
    ROBOT_STATUS = 13, "controller status (state port)"
    JOINT_TRAJ_PT_FULL = 14, "one trajectory point for one group"
    JOINT_FEEDBACK = 15, "joint feedback for one group (state port)"
    MOTO_MOTION_CTRL = 2001, "motion control command"
    MOTO_MOTION_REPLY = 2002, "reply to a motion request"
    MOTO_READ_IO_BIT = 2003, "read one IO bit"
    MOTO_READ_IO_BIT_REPLY = 2004, "value of one IO bit"
    MOTO_WRITE_IO_BIT = 2005, "write one IO bit"
    MOTO_WRITE_IO_BIT_REPLY = 2006, "result of an IO bit write"
    MOTO_READ_IO_GROUP = 2007, "read one IO byte (group)"
    MOTO_READ_IO_GROUP_REPLY = 2008, "value of one IO byte"
    MOTO_WRITE_IO_GROUP = 2009, "write one IO byte (group)"
    MOTO_WRITE_IO_GROUP_REPLY = 2010, "result of an IO byte write"
    MOTO_IOCTRL_REPLY = 2011, "IO control reply; defined but never sent"
    MOTO_READ_MREGISTER = 2012, "read an M-register; its reply reuses type 2012 (IO port only)"
    MOTO_WRITE_MREGISTER = 2013, "write an M-register; its reply reuses type 2013 (IO port only)"
    MOTO_JOINT_TRAJ_PT_FULL_EX = 2016, "one trajectory point for several groups"
    MOTO_JOINT_FEEDBACK_EX = 2017, "joint feedback of every group (state port, ≥ 2 groups)"
    MOTO_SELECT_TOOL = 2018, "select the tool file a group moves with"
    MOTO_GET_DH_PARAMETERS = 2020, "request the DH parameters; the reply reuses type 2020"


@enum.unique
class CommType(_Described):
    """Second header field (§1.2)."""

    INVALID = 0, "invalid"
    TOPIC = 1, "topic: a message nobody answers (state stream)"
    SERVICE_REQUEST = 2, "service request: the client expects a reply"
    SERVICE_REPLY = 3, "service reply"


@enum.unique
class ReplyType(_Described):
    """Third header field (§1.2). Motion replies always say SUCCESS; the outcome is in the body."""

    INVALID = 0, "not a reply (topics and requests)"
    SUCCESS = 1, "success"
    FAILURE = 2, "failure"


# --------------------------------------------------------------------------- body codes


@enum.unique
class MotionCommand(_Described):
    """MOTO_MOTION_CTRL commands (§1.7). No others exist in MotoROS v1."""

    CHECK_MOTION_READY = 200101, "is the controller ready to accept trajectory points?"
    CHECK_QUEUE_CNT = 200102, "number of increments queued for a group (returned in subcode)"
    STOP_MOTION = 200111, "stop at once and clear every queue"
    START_SERVOS = 200112, "switch servo power on"
    STOP_SERVOS = 200113, "stop motion and switch servo power off"
    RESET_ALARM = 200114, "reset alarms and cancel errors"
    START_TRAJ_MODE = 200121, "enter trajectory mode: servo on, start INIT_ROS, wait for ready"
    STOP_TRAJ_MODE = 200122, "leave trajectory mode: release INIT_ROS (OT#890)"
    DISCONNECT = 200130, "leave trajectory mode and close the motion connection"


class ResultCode(_Described):
    """``result`` of a MOTO_MOTION_REPLY (§1.7).

    Not unique on purpose: SimpleMessage.h aliases TRUE to SUCCESS and FALSE to
    FAILURE (CHECK_MOTION_READY answers TRUE/FALSE).
    """

    SUCCESS = 0, "success"
    TRUE = 0, "true"
    BUSY = 1, "busy: the previous point is still being processed, send it again"
    FAILURE = 2, "failure"
    FALSE = 2, "false"
    INVALID = 3, "invalid: the message or its data was refused (see subcode)"
    ALARM = 4, "alarm (defined, never sent by MotoROS 1.9.12)"
    NOT_READY = 5, "the controller is not ready for motion (see subcode)"
    MP_FAILURE = 6, "MotoPlus API failure (defined, never sent by MotoROS 1.9.12)"


@enum.unique
class InvalidSubcode(_Described):
    """Subcodes that go with ``ResultCode.INVALID`` (§1.7)."""

    UNSPECIFIED = 3000, "unspecified (never sent)"
    MSGSIZE = 3001, "message shorter than its type requires"
    MSGHEADER = 3002, "bad header (never sent)"
    MSGTYPE = 3003, "unknown or unsupported message type"
    GROUPNO = 3004, "group number out of range"
    SEQUENCE = 3005, "negative sequence number"
    COMMAND = 3006, "unknown motion command"
    DATA = 3010, "invalid data (never sent)"
    DATA_START_POS = 3011, "first point is more than 30 pulses from the commanded position"
    DATA_POSITION = 3012, "position out of range (never sent: MotoROS checks no limits)"
    DATA_SPEED = 3013, "velocity above the axis maximum"
    DATA_ACCEL = 3014, "acceleration out of range (never sent)"
    DATA_INSUFFICIENT = 3015, "time, position and velocity must all be valid"
    DATA_TIME = 3016, "point time at or beyond 4 hours (14400 s)"
    DATA_TOOLNO = 3017, "tool number outside 0..63"


@enum.unique
class NotReadySubcode(_Described):
    """Subcodes that go with ``ResultCode.NOT_READY`` (§1.7, §4.2).

    Declared as ``NAME = value, "meaning", "remedy"``: each reason carries, once, what
    the user does about it. The client's errors, ``pymotoros status``, the controller's
    refusal text and the web pendant all show this ``remedy``. START_TRAJ_MODE clears
    only what its §3.2 steps clear (errors, alarms, servo power, eco mode, MotoROS's
    latches, a job not started); it is refused while an E-stop, HOLD or not-REMOTE holds
    the robot, and cannot start INIT_ROS outside PLAY: those remedies begin with the
    operator's hand (``OPERATOR_FIRST``).
    """

    remedy: str

    def __new__(cls, value: int, meaning: str = "", remedy: str = "") -> Self:
        member = int.__new__(cls, value)
        member._value_ = value
        member.meaning = meaning
        member.remedy = remedy
        return member

    UNSPECIFIED = (
        5000,
        "not ready for an unspecified reason",
        "look at the pendant for what holds the robot, then enable trajectory mode again "
        "(START_TRAJ_MODE: `pymotoros enable`, RobotClient.enable())",
    )
    ALARM = (
        5001,
        "an alarm is active",
        "read the alarm on the pendant and remove its cause (a collision: move the robot "
        "clear); then reset it: START_TRAJ_MODE (`pymotoros enable`, RobotClient.enable()) "
        "resets alarms before it switches servo power on, RESET_ALARM (`pymotoros reset`, "
        "reset_alarm()) only resets",
    )
    ERROR = (
        5002,
        "an operator error is active",
        "remove the operator error's cause (shown on the pendant); START_TRAJ_MODE "
        "(`pymotoros enable`, RobotClient.enable()) or RESET_ALARM (`pymotoros reset`) "
        "cancels it",
    )
    ESTOP = (
        5003,
        "emergency stop is pressed",
        "an operator must release every emergency stop (pendant, controller, external): "
        "START_TRAJ_MODE is refused while one is pressed; once released, enable trajectory "
        "mode (START_TRAJ_MODE: `pymotoros enable`, RobotClient.enable()) to switch servo "
        "power on",
    )
    NOT_PLAY = (
        5004,
        "the pendant is not in PLAY mode",
        "an operator must turn the pendant's mode key to PLAY (START_TRAJ_MODE cannot "
        "start INIT_ROS in TEACH); then enable trajectory mode (START_TRAJ_MODE: "
        "`pymotoros enable`, RobotClient.enable())",
    )
    NOT_REMOTE = (
        5005,
        "the controller is not in REMOTE mode",
        "an operator must switch the controller to REMOTE (START_TRAJ_MODE is refused "
        "without it); then enable trajectory mode (START_TRAJ_MODE: `pymotoros enable`, "
        "RobotClient.enable())",
    )
    SERVO_OFF = (
        5006,
        "servo power is off (or eco mode is on)",
        "enable trajectory mode (START_TRAJ_MODE: `pymotoros enable`, RobotClient.enable()):"
        " it switches servo power on and leaves eco mode",
    )
    HOLD = (
        5007,
        "HOLD is on",
        "an operator must release HOLD (the pendant's key or the external hold input): "
        "START_TRAJ_MODE is refused while HOLD is on; then enable trajectory mode "
        "(START_TRAJ_MODE: `pymotoros enable`, RobotClient.enable()) to restart INIT_ROS",
    )
    NOT_STARTED = (
        5008,
        "the INIT_ROS job is not running",
        "enable trajectory mode (START_TRAJ_MODE: `pymotoros enable`, RobotClient.enable()):"
        " it starts INIT_ROS",
    )
    WAITING_ROS = (
        5009,
        "the INIT_ROS job has not raised OT#889 yet",
        "INIT_ROS runs but has not raised OT#889 yet: retry in a moment; if it persists, "
        "check the INIT_ROS job on the controller",
    )
    SKILLSEND = (
        5010,
        "motion-ready still false (DX100 SKILLSND, job-ready edge or stop pending)",
        "the job runs but motion is still not possible (DX100 SKILLSND, or a stop in "
        "progress): wait for the stop to end; if it persists, disable and enable trajectory"
        " mode again (STOP_TRAJ_MODE, START_TRAJ_MODE: `pymotoros disable`, `pymotoros "
        "enable`)",
    )
    PFL_ACTIVE = (
        5011,
        "a PFL (power and force limiting) event stopped the robot",
        "an operator must make the cell safe (move the robot clear of the contact) and "
        "release the PFL stop on the arm or pendant; only once the PFL signals are clear "
        "does enabling trajectory mode (START_TRAJ_MODE: `pymotoros enable`, "
        "RobotClient.enable()) clear MotoROS's latch",
    )
    INC_MOVE_ERROR = (
        5012,
        "the controller rejected an increment; restart trajectory mode",
        "look on the pendant for the alarm that refused the increment; then enable "
        "trajectory mode again (START_TRAJ_MODE: `pymotoros enable`, RobotClient.enable()),"
        " which clears the latch",
    )


OPERATOR_FIRST: Final = frozenset(
    {
        NotReadySubcode.ESTOP,
        NotReadySubcode.NOT_PLAY,
        NotReadySubcode.NOT_REMOTE,
        NotReadySubcode.HOLD,
        NotReadySubcode.PFL_ACTIVE,
    }
)
"""The reasons START_TRAJ_MODE cannot clear: a person must act first (§3.2 steps 4 and
9.1; a PFL stop is released on the arm). Their remedies begin with "an operator must"."""


NOT_READY_SUBCODES: Final = range(5000, 6000)
"""Subcodes of the NOT_READY family (§1.7, §4.2): 5000..5999."""


def reply_result(result: int, subcode: int) -> int:
    """The result a MOTO_MOTION_REPLY stands for.

    CHECK_MOTION_READY answers FALSE with a NOT_READY subcode (§3.1): the same cause as
    result 5, so it is read as NOT_READY; every other pair is what it says.
    """
    if result == ResultCode.FALSE and subcode in NOT_READY_SUBCODES:
        return int(ResultCode.NOT_READY)
    return result


@enum.unique
class StatusMode(_Described):
    """ROBOT_STATUS ``mode`` (§2.6): MotoROS sends 2 when the pendant is in PLAY, else 1."""

    TEACH = 1, "the pendant is not in PLAY (TEACH)"
    PLAY = 2, "the pendant is in PLAY"

    @classmethod
    def encode(cls, play: bool) -> StatusMode:
        """What the state server sends for a pendant in PLAY (``play``) or not."""
        return cls.PLAY if play else cls.TEACH

    @classmethod
    def is_play(cls, mode: int) -> bool:
        """How a client reads the field: PLAY only for 2 (anything else is not PLAY)."""
        return mode == cls.PLAY


class PendantMode(enum.Enum):
    """The pendant's mode key in words, as the operator turns it (the twin's controller)
    and as a client reads it back from ROBOT_STATUS ``mode`` (:class:`StatusMode`).
    One enum for both sides: ``pymotoros.client.Mode`` is this class."""

    TEACH = "teach"
    PLAY = "play"


@enum.unique
class IoResultCode(_Described):
    """``resultCode`` in IO reply bodies (§1.7, §6.1). Never a MOTION_REPLY subcode."""

    OK = 0, "ok"
    READ_ADDRESS_INVALID = 1001, "address not readable on this controller"
    WRITE_ADDRESS_INVALID = 1002, "address not writable on this controller"
    WRITE_VALUE_INVALID = 1003, "value out of range for this address"
    READ_API_ERROR = 1004, "the controller's IO read failed"
    WRITE_API_ERROR = 1005, "the controller's IO write failed"


class ValidFields(enum.IntFlag):
    """Bit mask of the optional fields of a trajectory point or feedback record."""

    TIME = 1
    POSITION = 2
    VELOCITY = 4
    ACCELERATION = 8


REQUIRED_POINT_FIELDS: Final = ValidFields.TIME | ValidFields.POSITION | ValidFields.VELOCITY
"""MotoROS refuses a point without all three (3015); acceleration is never used (§3.4)."""


def subcode_meaning(result: int, subcode: int) -> str:
    """Human text for a (result, subcode) pair as a MOTO_MOTION_REPLY carries it."""
    if result == ResultCode.INVALID:
        return InvalidSubcode.describe(subcode)
    if result == ResultCode.NOT_READY:
        return NotReadySubcode.describe(subcode)
    return ResultCode.describe(result) if subcode == 0 else f"subcode {subcode}"
