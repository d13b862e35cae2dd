"""How MotoROS waits for a condition: every 50 ms, for up to 5 s (§5.1)."""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Final

from pymotoros.controller.processes import ControllerClock

POLL_MS: Final = 50
"""MotoROS checks a condition it waits for every 50 ms (§5.1) …"""
POLL_LIMIT_MS: Final = 5000
"""… for up to 5 s."""

Waiting = Generator[int, None, bool]
"""A wait inside a process: yields sleep times, returns whether the condition came true."""


def wait_until(clock: ControllerClock, condition: Callable[[], bool]) -> Waiting:
    """Check ``condition`` every 50 ms for up to 5 s; True if it came true."""
    start = clock.time_ms
    while not condition():
        if clock.time_ms - start >= POLL_LIMIT_MS:
            return False
        yield POLL_MS
    return True
