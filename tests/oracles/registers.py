"""The S1CxG register outputs' reference route: every word computed in every tick.

The library keeps a tick's inputs and computes the words when an M-register is read or
written (``RegisterOutputs.step`` then ``materialise``). A real controller writes them
every interpolation period; :func:`every_tick` makes a controller do that, so the
equality tests can compare every reader's words with the eager controller's.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import MethodType

from pymotoros.controller import VirtualController
from pymotoros.controller.registers import HasTool, RegisterOutputs
from pymotoros.controller.servo import ServoGroup


def step_every_tick(
    self: RegisterOutputs,
    servos: Sequence[ServoGroup],
    interpolators: Sequence[HasTool],
    tick: int,
    powered: bool,
) -> None:
    """Compute and write every output from the servos' state now, in the tick."""
    self._pending = None
    for plan in self._plans:
        self._write(plan, servos[plan.index], interpolators[plan.index].tool, tick, powered)


def every_tick(vc: VirtualController) -> VirtualController:
    """``vc``, its register outputs now computed in every tick (returned for chaining)."""
    outputs = vc._cycle._registers
    assert isinstance(outputs, RegisterOutputs)
    outputs.step = MethodType(step_every_tick, outputs)  # type: ignore[method-assign]
    return vc
