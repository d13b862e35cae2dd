"""The web pendant: a page at ``/`` that shows and operates the virtual controller.

The page (HTML, CSS and vanilla JavaScript in ``static/``, shipped as package data) is
served by the control API's FastAPI application, so it works with no internet: no
CDN, no web font. Its buttons call the same ``POST /api/...`` endpoints as scripts do
(guarded against other origins by :class:`~pymotoros.runtime.csrf.CsrfGuard`).

Live state reaches the browser over one WebSocket, ``/ws/state`` (Starlette's
WebSocket support, no hand-rolled framing). One feed task builds the state document
every :data:`FEED_PERIOD_S` (10 ticks at 4 ms, right after a tick when the simulator
passes its ticker) and hands the *latest* one, JSON-encoded once, to every open tab: the cost on
the event loop is one snapshot per period whatever the number of tabs, and a slow tab
skips frames instead of queueing them. The document is built from the controller's
frozen snapshot with plain dicts (:mod:`.document`), not through the control API's
pydantic models: it is the only per-period work the pendant adds to the loop.

The 3D view is drawn by the page on a ``<canvas>`` from the joint positions of each
group's kinematic chain (:class:`.document.Skeleton`, the ``xyz`` of
:meth:`pymotoros.kinematics.Chain.joint_frames`), computed here for the feedback and the
command (the "ghost").
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import json
import logging
from collections.abc import Awaitable, Callable
from importlib.resources import files
from typing import Any, Final

from fastapi import FastAPI, WebSocket, WebSocketDisconnect
from fastapi.responses import FileResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles

from pymotoros.controller.api import ControllerSnapshot
from pymotoros.errors import KinematicsError
from pymotoros.kinematics import chain_for
from pymotoros.runtime.pendant.document import Ports, Skeleton, errors_document, state_document
from pymotoros.runtime.target import SimulatedController
from pymotoros.runtime.ticker import TickStats

__all__ = ["FEED_PERIOD_S", "PendantDocument", "PendantFeed", "install_pendant"]

logger = logging.getLogger(__name__)

FEED_PERIOD_S: Final = 0.04
"""25 Hz: the issue asks for at least 20 Hz; 40 ms leaves headroom on a busy machine."""

DEFAULT_PERIOD_MS: Final = 4
"""YRC1000's interpolation period, for a controller that does not say its own."""

MOTOROS_FIRST_OUTPUT: Final = 889
"""OT#889..896: the outputs INIT_ROS and MotoROS use (motoros-1.9.12.md)."""
MOTOROS_OUTPUTS: Final = 8
OT889_ADDRESS: Final = 11120
"""IO address of OT#889 (controller/readiness.py: ros_ready)."""

STATIC_DIR: Final = files("pymotoros.runtime.pendant") / "static"


class PendantFeed:
    """Builds the pendant's state document at :data:`FEED_PERIOD_S` while a tab listens.

    ``build`` returns the whole document (:class:`PendantDocument`). The task runs only
    while at least one tab is connected.
    """

    def __init__(
        self,
        build: Callable[[], dict[str, Any]],
        period_s: float = FEED_PERIOD_S,
        pace: Callable[[], Awaitable[None]] | None = None,
    ) -> None:
        self._build = build
        self._pace = pace
        self._period_s = period_s
        self._latest: str | None = None
        self._seq = 0
        self._changed = asyncio.Condition()
        self._listeners = 0
        self._task: asyncio.Task[None] | None = None

    @property
    def listeners(self) -> int:
        return self._listeners

    def document(self) -> dict[str, Any]:
        """One state document with the joint positions (also ``GET /api/pendant/state``)."""
        return self._build()

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time()
        while self._listeners > 0:
            try:
                doc = self.document()
            except Exception:  # a broken snapshot must not kill the page's feed silently
                logger.exception("pendant feed: building the state failed")
                raise
            text = json.dumps(doc, separators=(",", ":"))  # once, whatever the number of tabs
            async with self._changed:
                self._latest = text
                self._seq += 1
                self._changed.notify_all()
            if self._pace is not None:
                await self._pace()
                continue
            # absolute deadlines: the build's duration does not stretch the period
            deadline += self._period_s
            delay = deadline - loop.time()
            if delay < 0:
                deadline = loop.time()
                delay = 0
            await asyncio.sleep(delay)

    async def serve(self, ws: WebSocket) -> None:
        """Send the latest document to ``ws`` each time a new one is built."""
        await ws.accept()
        self._listeners += 1
        if self._task is None or self._task.done():
            self._task = asyncio.create_task(self._run(), name="pendant-feed")
        seen = [-1]  # the sequence number of the document sent last
        try:
            while True:
                async with self._changed:
                    await self._changed.wait_for(
                        lambda: self._latest is not None and self._seq != seen[0]
                    )
                    seen[0], doc = self._seq, self._latest or ""
                await ws.send_text(doc)
        except (WebSocketDisconnect, RuntimeError):
            pass  # the tab closed; RuntimeError: sent after the close
        finally:
            self._listeners -= 1
            if self._listeners == 0 and self._task is not None:
                self._task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await self._task
                self._task = None


class PendantDocument:
    """The pendant's document: ``GET /api/state``'s, each group's joint positions for the
    3D view (``frames``), and under ``pendant`` what a pendant shows beyond the control
    API: eco mode, the operator errors, why motion is not ready, the INIT_ROS job's line,
    MotoROS's outputs, the clients per port. Each extra only where the controller offers
    it (a test double may not)."""

    def __init__(
        self,
        controller: SimulatedController,
        tick_stats: Callable[[], TickStats],
        ports: Callable[[], Ports] | None = None,
        clients: Callable[[], dict[str, int]] | None = None,
    ) -> None:
        self._snapshot = controller.snapshot
        self._controller = controller
        self._tick_stats = tick_stats
        self._ports = ports
        self._clients = clients
        self._skeletons: list[Skeleton | None] = []
        cell = getattr(controller, "cell", None)
        for group in getattr(cell, "groups", ()):
            try:
                self._skeletons.append(Skeleton(chain_for(group)))
            except KinematicsError:
                self._skeletons.append(None)

    def __call__(self) -> dict[str, Any]:
        snapshot = self._snapshot()
        ports = self._ports() if self._ports is not None else (None, None, None)
        doc = state_document(snapshot, self._tick_stats(), ports)
        skeletons = self._skeletons
        for i, group in enumerate(doc["groups"]):
            skeleton = skeletons[i] if i < len(skeletons) else None
            if skeleton is None or len(group["feedback_rad"]) != skeleton.num_joints:
                group["frames"] = None  # no kinematic model: no 3D view for this group
                continue
            group["frames"] = {
                "feedback": skeleton.points(group["feedback_rad"]),
                "command": skeleton.points(group["command_rad"]),
            }
        doc["pendant"] = self._extras(snapshot)
        return doc

    def _extras(self, snapshot: ControllerSnapshot) -> dict[str, Any]:
        controller = self._controller
        out: dict[str, Any] = {"errors": errors_document(snapshot)}
        operator = getattr(controller, "operator_state", None)  # VirtualController's
        if operator is not None:
            out["eco"] = bool(operator.eco)
        motoros = getattr(controller, "motoros", None)
        reason = getattr(motoros, "not_ready_reason", None)
        if reason is not None:
            code, name, meaning, why = reason()
            out["not_ready"] = {"subcode": code, "name": name, "meaning": meaning, "why": why}
        jobs = getattr(controller, "job_position", None)  # a property of VirtualController
        if jobs is not None:
            out["jobs"] = [{"job": job, "line": line} for job, line in jobs]
        read_bit = getattr(controller, "read_io_bit", None)
        if read_bit is not None:
            out["outputs"] = [
                {
                    "name": f"OT#{MOTOROS_FIRST_OUTPUT + i}",
                    "value": read_bit(OT889_ADDRESS + i).value,
                }
                for i in range(MOTOROS_OUTPUTS)
            ]
        if self._clients is not None:
            out["clients"] = self._clients()
        return out


def install_pendant(
    app: FastAPI,
    controller: SimulatedController,
    tick_stats: Callable[[], TickStats],
    ports: Callable[[], Ports] | None = None,
    clients: Callable[[], dict[str, int]] | None = None,
    after_ticks: Callable[[int], Awaitable[None]] | None = None,
) -> None:
    """Serve the pendant at ``/`` (assets under ``/pendant``) and its feed at ``/ws/state``.

    ``after_ticks(n)`` (the interpolation loop's ``Ticker.wait_ticks``) paces the feed
    on the loop: each document is built right after a tick, so its work falls in the
    idle part of a period instead of colliding with the next tick's deadline.
    """
    pace: Callable[[], Awaitable[None]] | None = None
    if after_ticks is not None:
        period_ms = int(getattr(controller, "period_ms", DEFAULT_PERIOD_MS))
        ticks = max(1, round(FEED_PERIOD_S * 1000 / period_ms))
        pace = functools.partial(after_ticks, ticks)
    feed = PendantFeed(PendantDocument(controller, tick_stats, ports, clients), pace=pace)
    app.state.pendant_feed = feed
    app.mount("/pendant", StaticFiles(directory=str(STATIC_DIR)), name="pendant")

    @app.get("/", include_in_schema=False)
    async def pendant_page() -> FileResponse:
        return FileResponse(str(STATIC_DIR / "index.html"), media_type="text/html")

    @app.get("/favicon.ico", include_in_schema=False)
    async def favicon() -> RedirectResponse:
        return RedirectResponse("/docs/assets/favicon-32x32.png")

    @app.get("/api/pendant/state", tags=["state"])
    async def pendant_state() -> dict[str, Any]:
        """The pendant's document: ``GET /api/state`` plus each group's joint positions
        (``frames.feedback``/``frames.command``: x, y, z in m per joint, then flange,
        tool0 and tcp) for the 3D view."""
        return feed.document()

    @app.websocket("/ws/state")
    async def state_ws(ws: WebSocket) -> None:
        await feed.serve(ws)
