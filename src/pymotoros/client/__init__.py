"""Drive a MotoROS controller (a real robot or ``pymotoros sim``) from Python.

Async first (:class:`RobotClient`), with a blocking facade (:class:`SyncRobotClient`)
forwarding to it. The client speaks only the wire; see ``docs/client.md``. Every
exception here is a :class:`ClientError`, itself a ``pymotoros.errors.PymotorosError``.
The same names are at the front door (``import pymotoros``).
"""

from pymotoros.client.connection import Ports
from pymotoros.client.errors import (
    AxisDeviation,
    BusyTimeoutError,
    ClientError,
    CommandFailedError,
    ConnectError,
    ConnectionLostError,
    GroupError,
    InvalidRequestError,
    IoAddressError,
    IoError,
    ModelMismatchError,
    MotionConnectionLostError,
    MotionIncompleteError,
    MotionTimeoutError,
    MoveInProgressError,
    MoveStoppedError,
    NotReadyError,
    ReplyError,
    RequestTimeoutError,
    SpeedLimitError,
    StartPositionError,
    StateStreamLostError,
)
from pymotoros.client.following import FollowingReport, FollowingSample
from pymotoros.client.motion_port import MotionPort, MotionReadiness, StateSource
from pymotoros.client.move_result import MoveResult, StreamStats
from pymotoros.client.planning import (
    JointLimits,
    JointTrajectory,
    PlanningError,
    TrajectoryPoint,
    plan_joint_move,
)
from pymotoros.client.robot import RobotClient, connect
from pymotoros.client.srdf import NamedPose, NamedPoseError, parse_srdf
from pymotoros.client.state import JointState, Mode, RobotState, Status
from pymotoros.client.streaming import TrajectoryStreamer
from pymotoros.client.sync import SyncRobotClient
from pymotoros.client.timing import REAL_TIME, ClientClock

__all__ = [
    "REAL_TIME",
    "AxisDeviation",
    "BusyTimeoutError",
    "ClientClock",
    "ClientError",
    "CommandFailedError",
    "ConnectError",
    "ConnectionLostError",
    "FollowingReport",
    "FollowingSample",
    "GroupError",
    "InvalidRequestError",
    "IoAddressError",
    "IoError",
    "JointLimits",
    "JointState",
    "JointTrajectory",
    "Mode",
    "ModelMismatchError",
    "MotionConnectionLostError",
    "MotionIncompleteError",
    "MotionPort",
    "MotionReadiness",
    "MotionTimeoutError",
    "MoveInProgressError",
    "MoveResult",
    "MoveStoppedError",
    "NamedPose",
    "NamedPoseError",
    "NotReadyError",
    "PlanningError",
    "Ports",
    "ReplyError",
    "RequestTimeoutError",
    "RobotClient",
    "RobotState",
    "SpeedLimitError",
    "StartPositionError",
    "StateSource",
    "StateStreamLostError",
    "Status",
    "StreamStats",
    "SyncRobotClient",
    "TrajectoryPoint",
    "TrajectoryStreamer",
    "connect",
    "parse_srdf",
    "plan_joint_move",
]
