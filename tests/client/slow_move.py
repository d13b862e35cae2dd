"""A blocking move on its own thread, for tests that end it from the test's thread.

The move is slow (speed 1 %, about 100 s of virtual motion for 2.5 rad): the sync
twin's virtual time runs as fast as its thread, so a brisk move could end before the
test's stop or close arrives.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass

from pymotoros.client import SyncRobotClient


@dataclass
class SlowMove:
    """``client.move_joints(goal)`` running on ``thread``; what it raised lands in ``errors``."""

    thread: threading.Thread
    errors: list[BaseException]

    def error(self) -> BaseException:
        """The one exception the move ended with, once its thread has ended."""
        self.thread.join(10)
        assert not self.thread.is_alive()
        assert len(self.errors) == 1
        return self.errors[0]


def start_slow_move(client: SyncRobotClient, goal: Sequence[float]) -> SlowMove:
    """Start the move on a thread; return once its first progress sample came."""
    moving = threading.Event()
    errors: list[BaseException] = []

    def run() -> None:
        try:
            client.move_joints(goal, speed_scale=0.01, on_progress=lambda _s: moving.set())
        except BaseException as exc:
            errors.append(exc)

    move = SlowMove(threading.Thread(target=run), errors)
    move.thread.start()
    assert moving.wait(10)
    return move
