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

The names are declared once, in the table ``_EXPORTS`` (module -> names): ``__all__`` and
the lazy look-up follow from it. The ``TYPE_CHECKING`` imports repeat it for type
checkers, and a test holds them equal.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any, Final

if TYPE_CHECKING:
    from pymotoros.client.connection import Ports as Ports
    from pymotoros.client.errors import AxisDeviation as AxisDeviation
    from pymotoros.client.errors import BusyTimeoutError as BusyTimeoutError
    from pymotoros.client.errors import ClientError as ClientError
    from pymotoros.client.errors import CommandFailedError as CommandFailedError
    from pymotoros.client.errors import ConnectError as ConnectError
    from pymotoros.client.errors import ConnectionLostError as ConnectionLostError
    from pymotoros.client.errors import GroupError as GroupError
    from pymotoros.client.errors import InvalidRequestError as InvalidRequestError
    from pymotoros.client.errors import IoAddressError as IoAddressError
    from pymotoros.client.errors import IoError as IoError
    from pymotoros.client.errors import ModelMismatchError as ModelMismatchError
    from pymotoros.client.errors import MotionIncompleteError as MotionIncompleteError
    from pymotoros.client.errors import MotionTimeoutError as MotionTimeoutError
    from pymotoros.client.errors import MoveInProgressError as MoveInProgressError
    from pymotoros.client.errors import MoveStoppedError as MoveStoppedError
    from pymotoros.client.errors import NotReadyError as NotReadyError
    from pymotoros.client.errors import ReplyError as ReplyError
    from pymotoros.client.errors import RequestTimeoutError as RequestTimeoutError
    from pymotoros.client.errors import SpeedLimitError as SpeedLimitError
    from pymotoros.client.errors import StartPositionError as StartPositionError
    from pymotoros.client.motion_port import MotionReadiness as MotionReadiness
    from pymotoros.client.planning import JointLimits as JointLimits
    from pymotoros.client.planning import JointTrajectory as JointTrajectory
    from pymotoros.client.planning import PlanningError as PlanningError
    from pymotoros.client.planning import TrajectoryPoint as TrajectoryPoint
    from pymotoros.client.planning import plan_joint_move as plan_joint_move
    from pymotoros.client.robot import RobotClient as RobotClient
    from pymotoros.client.robot import connect as connect
    from pymotoros.client.srdf import NamedPose as NamedPose
    from pymotoros.client.srdf import NamedPoseError as NamedPoseError
    from pymotoros.client.srdf import parse_srdf as parse_srdf
    from pymotoros.client.state import JointState as JointState
    from pymotoros.client.state import Mode as Mode
    from pymotoros.client.state import RobotState as RobotState
    from pymotoros.client.state import Status as Status
    from pymotoros.client.streaming import FollowingReport as FollowingReport
    from pymotoros.client.streaming import FollowingSample as FollowingSample
    from pymotoros.client.streaming import MoveResult as MoveResult
    from pymotoros.client.sync import SyncRobotClient as SyncRobotClient
    from pymotoros.client.timing import ClientClock as ClientClock
    from pymotoros.controller import CellConfig as CellConfig
    from pymotoros.controller import VirtualController as VirtualController
    from pymotoros.controller import default_cell as default_cell
    from pymotoros.controller import load_cell as load_cell
    from pymotoros.controller.scenario import Scenario as Scenario
    from pymotoros.controller.scenario import load_scenario as load_scenario
    from pymotoros.controller.scenario import parse_scenario as parse_scenario
    from pymotoros.errors import ConfigError as ConfigError
    from pymotoros.errors import JobError as JobError
    from pymotoros.errors import KinematicsError as KinematicsError
    from pymotoros.errors import LocalProtocolError as LocalProtocolError
    from pymotoros.errors import PathBlockedError as PathBlockedError
    from pymotoros.errors import ProtocolError as ProtocolError
    from pymotoros.errors import PymotorosError as PymotorosError
    from pymotoros.errors import RemoteProtocolError as RemoteProtocolError
    from pymotoros.errors import TrajectoryRejectedError as TrajectoryRejectedError
    from pymotoros.kinematics import Chain as Chain
    from pymotoros.kinematics import chain_for as chain_for
    from pymotoros.models import AxisModel as AxisModel
    from pymotoros.models import ControllerModel as ControllerModel
    from pymotoros.models import ControllerType as ControllerType
    from pymotoros.models import DhLink as DhLink
    from pymotoros.models import GroupModel as GroupModel
    from pymotoros.models import RobotModel as RobotModel
    from pymotoros.models import controller_model as controller_model
    from pymotoros.models import robot_model as robot_model
    from pymotoros.trajectory import CheckReport as CheckReport
    from pymotoros.trajectory import Trajectory as Trajectory
    from pymotoros.trajectory import check_trajectory as check_trajectory
    from pymotoros.trajectory import plan_waypoints as plan_waypoints
    from pymotoros.trajectory import read_trajectory_file as read_trajectory_file
    from pymotoros.trajectory import write_trajectory_file as write_trajectory_file

_EXPORTS: Final[dict[str, tuple[str, ...]]] = {
    "pymotoros.client.connection": ("Ports",),
    "pymotoros.client.errors": (
        "AxisDeviation",
        "BusyTimeoutError",
        "ClientError",
        "CommandFailedError",
        "ConnectError",
        "ConnectionLostError",
        "GroupError",
        "InvalidRequestError",
        "IoAddressError",
        "IoError",
        "ModelMismatchError",
        "MotionIncompleteError",
        "MotionTimeoutError",
        "MoveInProgressError",
        "MoveStoppedError",
        "NotReadyError",
        "ReplyError",
        "RequestTimeoutError",
        "SpeedLimitError",
        "StartPositionError",
    ),
    "pymotoros.client.motion_port": ("MotionReadiness",),
    "pymotoros.client.planning": (
        "JointLimits",
        "JointTrajectory",
        "PlanningError",
        "TrajectoryPoint",
        "plan_joint_move",
    ),
    "pymotoros.client.robot": ("RobotClient", "connect"),
    "pymotoros.client.srdf": ("NamedPose", "NamedPoseError", "parse_srdf"),
    "pymotoros.client.state": ("JointState", "Mode", "RobotState", "Status"),
    "pymotoros.client.streaming": ("FollowingReport", "FollowingSample", "MoveResult"),
    "pymotoros.client.sync": ("SyncRobotClient",),
    "pymotoros.client.timing": ("ClientClock",),
    "pymotoros.controller": ("CellConfig", "VirtualController", "default_cell", "load_cell"),
    "pymotoros.controller.scenario": ("Scenario", "load_scenario", "parse_scenario"),
    "pymotoros.errors": (
        "ConfigError",
        "JobError",
        "KinematicsError",
        "LocalProtocolError",
        "PathBlockedError",
        "ProtocolError",
        "PymotorosError",
        "RemoteProtocolError",
        "TrajectoryRejectedError",
    ),
    "pymotoros.kinematics": ("Chain", "chain_for"),
    "pymotoros.models": (
        "AxisModel",
        "ControllerModel",
        "ControllerType",
        "DhLink",
        "GroupModel",
        "RobotModel",
        "controller_model",
        "robot_model",
    ),
    "pymotoros.trajectory": (
        "CheckReport",
        "Trajectory",
        "check_trajectory",
        "plan_waypoints",
        "read_trajectory_file",
        "write_trajectory_file",
    ),
}
"""The front door's one declaration: each defining module and the names it lends to it.

A literal, not read from the ``TYPE_CHECKING`` imports above at run time: those are for
type checkers only (``X as X`` is an explicit re-export), and ``tests/test_front_door.py``
holds them equal to this table, so the two cannot drift."""

_WHERE: Final[dict[str, str]] = {
    name: module for module, names in _EXPORTS.items() for name in names
}
"""Name -> defining module, for :func:`__getattr__`."""
__all__ = sorted([*_WHERE, "__version__"])


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
