"""pymotoros.runtime: the virtual controller on the network.

The MotoROS servers (motion 50240, state 50241, IO 50242), the interpolation loop on
an injected clock, and the HTTP control API, all owned by :class:`SimulatorApp`::

    from pymotoros.controller import default_cell
    from pymotoros.runtime import SimulatorApp, SimulatorConfig

    async with SimulatorApp.for_cell(default_cell(), SimulatorConfig(motion_port=0)) as app:
        print(app.ports)

Names are imported on first use, so ``pymotoros.runtime.clock`` does not pull in the
web stack.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pymotoros.runtime.app import BoundPorts, SimulatorApp, SimulatorConfig
    from pymotoros.runtime.clock import Clock, LoopClock, ManualClock
    from pymotoros.runtime.http_api import create_http_app
    from pymotoros.runtime.realtime import request_realtime
    from pymotoros.runtime.ticker import Ticker, TickStats

__all__ = [
    "BoundPorts",
    "Clock",
    "LoopClock",
    "ManualClock",
    "SimulatorApp",
    "SimulatorConfig",
    "TickStats",
    "Ticker",
    "create_http_app",
    "request_realtime",
]

_WHERE = {
    "BoundPorts": "app",
    "SimulatorApp": "app",
    "SimulatorConfig": "app",
    "Clock": "clock",
    "LoopClock": "clock",
    "ManualClock": "clock",
    "create_http_app": "http_api",
    "request_realtime": "realtime",
    "TickStats": "ticker",
    "Ticker": "ticker",
}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)
