"""What a simulator and a fleet of them share: served in the background once entered.

``async with`` starts serving in a task (:attr:`Served._task`, set by the subclass's
``__aenter__``); leaving the block, :meth:`Served.stop` or a signal
(:meth:`Served.request_stop`) ends it, and :meth:`Served.wait_stopped` re-raises what
ended it if it crashed.
"""

from __future__ import annotations

import asyncio

__all__ = ["Served"]


class Served:
    """One stop request and one serving task, for ``async with`` servers."""

    _what = "server"
    """How errors name it (``simulator``, ``fleet``)."""

    def __init__(self) -> None:
        self._stop = asyncio.Event()
        self._task: asyncio.Task[None] | None = None

    def request_stop(self) -> None:
        """Ask it to shut down (safe from a signal handler; idempotent)."""
        self._stop.set()

    async def wait_stopped(self) -> None:
        """Wait until it has shut down (after :meth:`request_stop`, a signal, or a
        crash, which this re-raises)."""
        if self._task is None:
            raise RuntimeError(f"wait_stopped() needs the {self._what} started with `async with`")
        await asyncio.shield(self._task)

    async def stop(self) -> None:
        """Shut down and wait until everything is released (idempotent)."""
        self.request_stop()
        task = self._task
        if task is not None and not task.done():
            await task

    async def __aexit__(self, *exc_info: object) -> None:
        await self.stop()
