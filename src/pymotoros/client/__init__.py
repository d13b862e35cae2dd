"""Drive a MotoROS controller (a real robot or ``pymotoros sim``) from Python.

Async first (:class:`RobotClient`), with a blocking facade (:class:`SyncRobotClient`)
forwarding to it. The client speaks only the wire; see ``docs/client.md``.
"""

from pymotoros.client.connection import Ports
from pymotoros.client.errors import (
    AxisDeviation,
    BusyTimeoutError,
    ClientError,
    CommandFailedError,
    ConnectError,
    ConnectionLostError,
    InvalidRequestError,
    IoAddressError,
    IoError,
    MotionIncompleteError,
    MotionTimeoutError,
    NotReadyError,
    ReplyError,
    RequestTimeoutError,
    SpeedLimitError,
    StartPositionError,
)
from pymotoros.client.planning import JointLimits, JointTrajectory, TrajectoryPoint, plan_joint_move
from pymotoros.client.robot import Readiness, RobotClient, connect
from pymotoros.client.srdf import NamedPose, parse_srdf
from pymotoros.client.state import JointState, Mode, RobotState, Status
from pymotoros.client.streaming import FollowingReport, FollowingSample, MoveResult
from pymotoros.client.sync import SyncRobotClient

__all__ = [
    "AxisDeviation",
    "BusyTimeoutError",
    "ClientError",
    "CommandFailedError",
    "ConnectError",
    "ConnectionLostError",
    "FollowingReport",
    "FollowingSample",
    "InvalidRequestError",
    "IoAddressError",
    "IoError",
    "JointLimits",
    "JointState",
    "JointTrajectory",
    "Mode",
    "MotionIncompleteError",
    "MotionTimeoutError",
    "MoveResult",
    "NamedPose",
    "NotReadyError",
    "Ports",
    "Readiness",
    "ReplyError",
    "RequestTimeoutError",
    "RobotClient",
    "RobotState",
    "SpeedLimitError",
    "StartPositionError",
    "Status",
    "SyncRobotClient",
    "TrajectoryPoint",
    "connect",
    "parse_srdf",
    "plan_joint_move",
]
