"""The scenario slot of a controller: the loaded scenario's driver and what it has fired.

A controller runs at most one scenario at a time; loading another replaces the events
not fired yet while the record of fired events carries on (it is the controller's
history, shown in its snapshot).
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from pymotoros.controller.scenario import FiredEvent, Scenario, ScenarioDriver, ScenarioEvent

logger = logging.getLogger(__name__)


class ScenarioPlayer:
    """Fires the loaded scenario's events from the tick and keeps the fired record."""

    def __init__(self, read_io: Callable[[int], int]) -> None:
        self._read_io = read_io
        self._driver: ScenarioDriver | None = None
        self.loaded = False
        """A scenario was loaded (the tick skips the player until then)."""
        self._fired: list[FiredEvent] = []

    def load(
        self, scenario: Scenario, perform: Callable[[ScenarioEvent], None], now_ms: int
    ) -> None:
        """Run ``scenario``'s events from the next tick (replacing events not fired yet)."""
        driver = ScenarioDriver(scenario, perform=perform, read_io=self._read_io, now_ms=now_ms)
        driver.fired = self._fired
        self._driver = driver
        self.loaded = True
        logger.info("scenario %s: %d events", scenario.source, len(scenario.events))

    def tick(self, now_ms: int, moved: bool) -> None:
        """One tick of the loaded scenario, if any (``moved``: increments executed)."""
        if self._driver is not None:
            self._driver.tick(now_ms, moved)

    @property
    def fired(self) -> tuple[FiredEvent, ...]:
        """Scenario events fired so far (time since boot, action, parameters, refusal)."""
        return tuple(self._fired)
