"""The virtual controller: a Yaskawa controller running MotoROS 1.9.12, in virtual time.

Front door::

    from pymotoros.controller import VirtualController, default_cell, load_cell

    vc = VirtualController(load_cell("cell.toml"))   # or VirtualController() for HC10/YRC1000
    vc.tick()                                        # one interpolation period

The contract with the servers is :mod:`pymotoros.controller.api` (the protocols) over
:mod:`pymotoros.controller.values` (every value the controller hands out, a leaf).
"""

from pymotoros.controller.api import (
    AlarmInfo,
    ControllerSnapshot,
    FaultInjection,
    FeedbackData,
    GroupSnapshot,
    IoRead,
    MotoRosController,
    OperatorPanel,
    Outcome,
    Pending,
    PointData,
    StatusData,
)
from pymotoros.controller.cell import (
    CellConfig,
    InitialState,
    ServoConfig,
    ToolConfig,
    cell_from_dict,
    default_cell,
    load_cell,
)
from pymotoros.controller.controller import VirtualController
from pymotoros.controller.machine import EstopSource
from pymotoros.protocol.constants import PendantMode

__all__ = [
    "AlarmInfo",
    "CellConfig",
    "ControllerSnapshot",
    "EstopSource",
    "FaultInjection",
    "FeedbackData",
    "GroupSnapshot",
    "InitialState",
    "IoRead",
    "MotoRosController",
    "OperatorPanel",
    "Outcome",
    "PendantMode",
    "Pending",
    "PointData",
    "ServoConfig",
    "StatusData",
    "ToolConfig",
    "VirtualController",
    "cell_from_dict",
    "default_cell",
    "load_cell",
]
