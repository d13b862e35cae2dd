"""Robot and controller models as data, shared by controller, motion engine and client."""

from pymotoros.models.controllers import (
    CONTROLLERS,
    DEFAULT_CONTROLLER,
    ControllerModel,
    ControllerType,
    FloatMode,
    IoArea,
    IoRange,
    controller_model,
)
from pymotoros.models.fidelity import DEFAULT_FIDELITY, Fidelity
from pymotoros.models.robots import (
    DEFAULT_ROBOT,
    ROBOTS,
    AxisModel,
    DhLink,
    GroupKind,
    GroupModel,
    RobotModel,
    robot_model,
)

__all__ = [
    "CONTROLLERS",
    "DEFAULT_CONTROLLER",
    "DEFAULT_FIDELITY",
    "DEFAULT_ROBOT",
    "ROBOTS",
    "AxisModel",
    "ControllerModel",
    "ControllerType",
    "DhLink",
    "Fidelity",
    "FloatMode",
    "GroupKind",
    "GroupModel",
    "IoArea",
    "IoRange",
    "RobotModel",
    "controller_model",
    "robot_model",
]
