"""What the runtime drives: a controller that serves the wire *and* has an operator panel."""

from __future__ import annotations

from typing import Protocol

from pymotoros.controller.api import (
    FaultInjection,
    MotoRosController,
    OperatorPanel,
    SafetyPanel,
)

__all__ = ["SimulatedController"]


class SimulatedController(
    MotoRosController, OperatorPanel, FaultInjection, SafetyPanel, Protocol
):
    """``VirtualController`` satisfies this: the servers use one side, the HTTP API the rest."""
