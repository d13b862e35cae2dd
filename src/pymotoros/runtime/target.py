"""What the runtime drives: a controller that serves the wire *and* has an operator panel."""

from __future__ import annotations

from typing import Protocol

from pymotoros.controller.actions import ActionTarget
from pymotoros.controller.api import MotoRosController

__all__ = ["SimulatedController"]


class SimulatedController(MotoRosController, ActionTarget, Protocol):
    """``VirtualController`` satisfies this: the servers use one side, the HTTP API and the
    pendant the other (the declared actions' target)."""
