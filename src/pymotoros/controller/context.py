"""The shared parts every piece of MotoROS works with, handed over as one object.

MotoROS's parts (:mod:`~pymotoros.controller.readiness`,
:mod:`~pymotoros.controller.commands`, :mod:`~pymotoros.controller.trajectory`,
:mod:`~pymotoros.controller.incmove_task`, :mod:`~pymotoros.controller.skillsnd`,
:mod:`~pymotoros.controller.connections`) all reach the same controller through the
same few objects. :class:`MotoRosContext` bundles them, so a part's constructor says
only what is particular to it (usually the :class:`~pymotoros.controller.readiness.Readiness`
it consults) and adding a shared part does not ripple through every signature.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from pymotoros.controller.cell import CellConfig
from pymotoros.controller.inform import JobRunner
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.machine import OperatorMachine
from pymotoros.controller.processes import ControllerClock
from pymotoros.controller.queues import MotionQueues
from pymotoros.controller.servo import ServoGroup
from pymotoros.motion import GroupAxes, GroupInterpolator


@dataclass(frozen=True, slots=True)
class MotoRosContext:
    """What MotoPlus offers MotoROS on one controller (per-group tuples in group order)."""

    cell: CellConfig
    """The cell file as read: controller model, groups, tools, start-up options."""
    clock: ControllerClock
    """Controller time and tick count (MotoROS reads time, never advances it)."""
    io: IoImage
    """Every signal and M-register; MotoROS's only view of the operator state."""
    machine: OperatorMachine
    """The operator state, changed by the events MotoPlus offers (servo on, reset …)."""
    runner: JobRunner
    """The INFORM job tasks (INIT_ROS and its sub-jobs)."""
    queues: MotionQueues
    """Every group's increment queue, as MotoROS clears them."""
    axes: tuple[GroupAxes, ...]
    interpolators: tuple[GroupInterpolator, ...]
    servos: tuple[ServoGroup, ...]
    increment_clip: Callable[[], tuple[tuple[int, ...], ...] | None] | None = None
    """The controller's FSU clip per group and slot for this tick (None: no clip); MotoROS
    never calls it: the IncMove task uses it as the controller's increment function."""
    increment_tcp_clip: (
        Callable[[int, Sequence[int], Sequence[int]], Sequence[int] | None] | None
    ) = None
    """The FSU's TCP-speed clip of one group's intended increment (group, commanded
    pulses, increment) -> per-slot maximum, None when off; also the controller's side."""

    @property
    def num_groups(self) -> int:
        return len(self.axes)
