"""Server connection events: the feedback outputs OT#891..894 and the disconnect queue clear."""

from __future__ import annotations

import logging

from pymotoros.controller import signals
from pymotoros.controller.context import MotoRosContext

logger = logging.getLogger(__name__)


class ConnectionEvents:
    """What MotoROS does when a client connects to or leaves one of its servers."""

    def __init__(self, ctx: MotoRosContext) -> None:
        self._io = ctx.io
        self._queues = ctx.queues

    def motion_connected(self) -> None:
        self._io.set(signals.MOTION_SERVER_CONNECTED, 1)

    def motion_disconnected(self) -> None:
        self._io.set(signals.MOTION_SERVER_CONNECTED, 0)
        if self._queues.has_queued_motion():
            logger.info(
                "motion connection closed with increments queued: clearing them "
                "(MotoROS 1.9.12 would keep them and resume on the next connection)"
            )
        self._queues.clear()

    def state_clients_changed(self, count: int) -> None:
        self._io.set(signals.STATE_SERVER_CONNECTED, count > 0)

    def io_connected(self) -> None:
        self._io.set(signals.IO_SERVER_CONNECTED, 1)
