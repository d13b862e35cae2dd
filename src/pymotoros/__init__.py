"""pymotoros: a virtual Yaskawa Motoman controller running MotoROS, and a client for real robots.

The virtual controller speaks the ROS-Industrial Simple Message protocol exactly as
MotoROS 1.9.12 does (motion port 50240, state 50241, IO 50242); the client drives a
real controller and the twin the same way.

The front door: one name per concept, whatever sub-package defines it::

    import pymotoros

    async with pymotoros.RobotClient("192.168.1.31", robot="hc10") as robot:
        await robot.enable()
        await robot.move_named("home")

    try:
        ...
    except pymotoros.PymotorosError:       # every exception pymotoros raises on purpose
        ...

Every name is imported on first use (PEP 562): ``import pymotoros`` runs first for
any sub-package, and the sans-I/O codec (``pymotoros.protocol``) must load neither
asyncio nor socket. The in-memory twin for tests is :mod:`pymotoros.testing`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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
        MotionIncompleteError,
        MotionTimeoutError,
        MoveStoppedError,
        NotReadyError,
        ReplyError,
        RequestTimeoutError,
        SpeedLimitError,
        StartPositionError,
    )
    from pymotoros.client.motion_port import MotionReadiness
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
    from pymotoros.client.streaming import FollowingReport, FollowingSample, MoveResult
    from pymotoros.client.sync import SyncRobotClient
    from pymotoros.client.timing import ClientClock
    from pymotoros.controller import CellConfig, VirtualController, default_cell, load_cell
    from pymotoros.controller.scenario import Scenario, load_scenario, parse_scenario
    from pymotoros.errors import (
        ConfigError,
        JobError,
        KinematicsError,
        LocalProtocolError,
        ProtocolError,
        PymotorosError,
        RemoteProtocolError,
        TrajectoryRejectedError,
    )
    from pymotoros.kinematics import Chain, chain_for
    from pymotoros.models import (
        AxisModel,
        ControllerModel,
        ControllerType,
        DhLink,
        GroupModel,
        RobotModel,
        controller_model,
        robot_model,
    )
    from pymotoros.trajectory import (
        CheckReport,
        Trajectory,
        check_trajectory,
        plan_waypoints,
        read_trajectory_file,
        write_trajectory_file,
    )

_WHERE: dict[str, str] = {
    # the client
    "RobotClient": "pymotoros.client.robot",
    "connect": "pymotoros.client.robot",
    "SyncRobotClient": "pymotoros.client.sync",
    "Ports": "pymotoros.client.connection",
    "ClientClock": "pymotoros.client.timing",
    "MotionReadiness": "pymotoros.client.motion_port",
    "RobotState": "pymotoros.client.state",
    "JointState": "pymotoros.client.state",
    "Status": "pymotoros.client.state",
    "Mode": "pymotoros.client.state",
    "MoveResult": "pymotoros.client.streaming",
    "FollowingReport": "pymotoros.client.streaming",
    "FollowingSample": "pymotoros.client.streaming",
    "JointLimits": "pymotoros.client.planning",
    "JointTrajectory": "pymotoros.client.planning",
    "TrajectoryPoint": "pymotoros.client.planning",
    "plan_joint_move": "pymotoros.client.planning",
    "NamedPose": "pymotoros.client.srdf",
    "parse_srdf": "pymotoros.client.srdf",
    # kinematics
    "Chain": "pymotoros.kinematics",
    "chain_for": "pymotoros.kinematics",
    # trajectory files, waypoint timing and the offline pre-flight
    "Trajectory": "pymotoros.trajectory",
    "CheckReport": "pymotoros.trajectory",
    "check_trajectory": "pymotoros.trajectory",
    "plan_waypoints": "pymotoros.trajectory",
    "read_trajectory_file": "pymotoros.trajectory",
    "write_trajectory_file": "pymotoros.trajectory",
    # the virtual controller
    "VirtualController": "pymotoros.controller",
    "CellConfig": "pymotoros.controller",
    "default_cell": "pymotoros.controller",
    "load_cell": "pymotoros.controller",
    "Scenario": "pymotoros.controller.scenario",
    "load_scenario": "pymotoros.controller.scenario",
    "parse_scenario": "pymotoros.controller.scenario",
    # models (GroupModel and DhLink: the models' ones, not the HTTP or wire shapes)
    "RobotModel": "pymotoros.models",
    "GroupModel": "pymotoros.models",
    "AxisModel": "pymotoros.models",
    "DhLink": "pymotoros.models",
    "ControllerModel": "pymotoros.models",
    "ControllerType": "pymotoros.models",
    "robot_model": "pymotoros.models",
    "controller_model": "pymotoros.models",
    # the one exception tree
    "PymotorosError": "pymotoros.errors",
    "ProtocolError": "pymotoros.errors",
    "LocalProtocolError": "pymotoros.errors",
    "RemoteProtocolError": "pymotoros.errors",
    "ConfigError": "pymotoros.errors",
    "JobError": "pymotoros.errors",
    "KinematicsError": "pymotoros.errors",
    "TrajectoryRejectedError": "pymotoros.errors",
    "ClientError": "pymotoros.client.errors",
    "ConnectError": "pymotoros.client.errors",
    "ConnectionLostError": "pymotoros.client.errors",
    "RequestTimeoutError": "pymotoros.client.errors",
    "MotionTimeoutError": "pymotoros.client.errors",
    "MotionIncompleteError": "pymotoros.client.errors",
    "GroupError": "pymotoros.client.errors",
    "ModelMismatchError": "pymotoros.client.errors",
    "MoveStoppedError": "pymotoros.client.errors",
    "ReplyError": "pymotoros.client.errors",
    "NotReadyError": "pymotoros.client.errors",
    "InvalidRequestError": "pymotoros.client.errors",
    "StartPositionError": "pymotoros.client.errors",
    "SpeedLimitError": "pymotoros.client.errors",
    "CommandFailedError": "pymotoros.client.errors",
    "BusyTimeoutError": "pymotoros.client.errors",
    "IoError": "pymotoros.client.errors",
    "IoAddressError": "pymotoros.client.errors",
    "AxisDeviation": "pymotoros.client.errors",
    "PlanningError": "pymotoros.client.planning",
    "NamedPoseError": "pymotoros.client.srdf",
}

__all__ = [
    "AxisDeviation",
    "AxisModel",
    "BusyTimeoutError",
    "CellConfig",
    "Chain",
    "CheckReport",
    "ClientClock",
    "ClientError",
    "CommandFailedError",
    "ConfigError",
    "ConnectError",
    "ConnectionLostError",
    "ControllerModel",
    "ControllerType",
    "DhLink",
    "FollowingReport",
    "FollowingSample",
    "GroupError",
    "GroupModel",
    "InvalidRequestError",
    "IoAddressError",
    "IoError",
    "JobError",
    "JointLimits",
    "JointState",
    "JointTrajectory",
    "KinematicsError",
    "LocalProtocolError",
    "Mode",
    "ModelMismatchError",
    "MotionIncompleteError",
    "MotionReadiness",
    "MotionTimeoutError",
    "MoveResult",
    "MoveStoppedError",
    "NamedPose",
    "NamedPoseError",
    "NotReadyError",
    "PlanningError",
    "Ports",
    "ProtocolError",
    "PymotorosError",
    "RemoteProtocolError",
    "ReplyError",
    "RequestTimeoutError",
    "RobotClient",
    "RobotModel",
    "RobotState",
    "Scenario",
    "SpeedLimitError",
    "StartPositionError",
    "Status",
    "SyncRobotClient",
    "Trajectory",
    "TrajectoryPoint",
    "TrajectoryRejectedError",
    "VirtualController",
    "__version__",
    "chain_for",
    "check_trajectory",
    "connect",
    "controller_model",
    "default_cell",
    "load_cell",
    "load_scenario",
    "parse_scenario",
    "parse_srdf",
    "plan_joint_move",
    "plan_waypoints",
    "read_trajectory_file",
    "robot_model",
    "write_trajectory_file",
]


def __getattr__(name: str) -> Any:
    # Looked up lazily: importlib.metadata imports socket (through email), and the
    # sans-I/O codec must be importable without loading any networking module.
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("pymotoros")
        except PackageNotFoundError:  # a source tree that is not installed
            return "0.0.0"
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'pymotoros' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # the next look-up is a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
