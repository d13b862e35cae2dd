"""Server connection events: the feedback outputs OT#891..894, and what the motion
tasks do when the motion connection closes (fidelity exact or safe)."""

from __future__ import annotations

import logging

from pymotoros.controller import signals
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.incmove_task import IncMoveTask
from pymotoros.controller.lint import ResumedMotion
from pymotoros.models.fidelity import Fidelity

logger = logging.getLogger(__name__)


class ConnectionEvents:
    """What MotoROS does when a client connects to or leaves one of its servers."""

    def __init__(self, ctx: MotoRosContext, inc_move: IncMoveTask) -> None:
        self._io = ctx.io
        self._queues = ctx.queues
        self._inc_move = inc_move
        self._fidelity = ctx.cell.fidelity
        self._clock = ctx.clock

    def motion_connected(self) -> ResumedMotion | None:
        """OT#893 on; the motion tasks exist again. Not None when increments a closed
        connection left queued resume now, or (safe) would on a robot: see
        :meth:`resumes_motion`."""
        self._io.set(signals.MOTION_SERVER_CONNECTED, 1)
        resumed = self._inc_move.start_tasks()
        cleared, self._queues.cleared_at_close = self._queues.cleared_at_close, 0
        if resumed:
            return self.resumes_motion(ResumedMotion())
        if cleared:
            return self.resumes_motion(ResumedMotion(cleared * self._clock.period_ms / 1000.0))
        return None

    @staticmethod
    def resumes_motion(resumed: ResumedMotion) -> ResumedMotion:
        """The one place a connection is found to restart a closed connection's motion
        (§2.2): in fidelity exact the kept queues run now; in safe the twin cleared them
        at the close, and a robot would run them now."""
        if resumed.cleared_s is None:
            logger.warning(
                "motion connection opened while a closed connection's increments were "
                "queued: the robot resumes that motion now, as MotoROS 1.9.12 does "
                "(send STOP_MOTION first on connecting; docs/client.md)"
            )
        else:
            logger.info(
                "motion connection opened after a close that cleared %.3f s of queued "
                "increments (fidelity safe): MotoROS 1.9.12 would have kept them and "
                "resumed that motion now (send STOP_MOTION first on connecting; "
                "docs/client.md)",
                resumed.cleared_s,
            )
        return resumed

    def motion_disconnected(self) -> None:
        """OT#893 off; the IncMove and AddToIncQueue tasks end (§2.2).

        exact: the queues are kept, as MotoROS 1.9.12 keeps them, and the next motion
        connection resumes them. safe: every queue and pending point is cleared, so
        nothing moves for a client that left (our documented improvement).
        """
        self._io.set(signals.MOTION_SERVER_CONNECTED, 0)
        queued = self._queues.has_queued_motion()
        if self._fidelity is Fidelity.EXACT:
            self._inc_move.end_tasks()
            if queued:
                logger.info(
                    "motion connection closed with increments queued: kept, as MotoROS "
                    "1.9.12 keeps them; the next motion connection resumes them"
                )
            return
        if queued:
            logger.info(
                "motion connection closed with increments queued: clearing them "
                "(MotoROS 1.9.12 would keep them and resume on the next connection; "
                "fidelity safe)"
            )
        kept = self._queues.longest()
        self._queues.clear()
        self._queues.cleared_at_close = kept  # what a robot would resume (client lint)

    def state_clients_changed(self, count: int) -> None:
        self._io.set(signals.STATE_SERVER_CONNECTED, count > 0)

    def io_connected(self) -> None:
        self._io.set(signals.IO_SERVER_CONNECTED, 1)
