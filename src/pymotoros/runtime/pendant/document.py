"""The state document, built straight from the controller's frozen snapshot: the one
builder of ``GET /api/state``, ``/ws/state`` and the pendant.

The document is derived from the snapshot's declaration
(:mod:`pymotoros.runtime.snapshot_document`): a field added to
:class:`~pymotoros.controller.api.ControllerSnapshot` or one of its parts appears here
and in the control API's ``StateModel`` (the OpenAPI schema, derived from the same
declaration) with no other edit. The runtime adds what only it knows: the loop's
``tick`` statistics and the listening ``ports``.

The feed sends this document 25 times a second, on the event loop that also runs the
4 ms interpolation ticks, so every microsecond it takes is taken from the loop's idle
time. It is therefore built without pydantic: plain dicts and lists, by an encoder
compiled once per snapshot type, then JSON-encoded once for every tab. ``GET
/api/state`` answers the same dict; FastAPI checks it against ``StateModel``.

The 3D view needs each joint's position only (not the orientations
:meth:`pymotoros.kinematics.Chain.joint_frames` also computes): :class:`Skeleton` runs
Pinocchio's forward kinematics on the chain's model with its own workspace and reads
the translations, and reuses its answer while the joints stand still.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final

import numpy as np
import orjson
import pinocchio as pin

from pymotoros.controller.api import AlarmInfo, ControllerSnapshot
from pymotoros.kinematics import Chain
from pymotoros.runtime.snapshot_document import document_encoder
from pymotoros.runtime.ticker import TickStats

__all__ = ["END_FRAMES", "Skeleton", "encode", "state_document"]

END_FRAMES: Final = ("flange", "tool0", "tcp")
"""The frames drawn after the joints (the order of ``Chain.joint_frames``)."""

Ports = tuple[int | None, int | None, int | None]


class Skeleton:
    """Positions (m, ``base_link``) of a chain's joints, then flange, tool0 and tcp."""

    def __init__(self, chain: Chain) -> None:
        self._model = chain.model
        self._data = chain.model.createData()  # its own workspace: the chain's is shared
        self.num_joints = chain.num_joints
        self._frames = [int(self._model.getFrameId(name)) for name in END_FRAMES]
        self._last_q: tuple[float, ...] | None = None
        self._last: list[list[float]] = []

    def points(self, q: Sequence[float]) -> list[list[float]]:
        """The positions at ``q`` (ROS joint order, rad or m). Do not mutate the answer:
        it is reused for the next call at the same ``q``."""
        key = tuple(q)
        if key == self._last_q:
            return self._last
        if len(key) != self.num_joints:
            raise ValueError(f"expected {self.num_joints} joint values, got {len(key)}")
        data = self._data
        pin.framesForwardKinematics(self._model, data, np.array(key, dtype=float))
        joints, frames = data.oMi, data.oMf  # placements in the world (base_link)
        out = [joints[i].translation.tolist() for i in range(1, self.num_joints + 1)]
        out += [frames[f].translation.tolist() for f in self._frames]
        self._last_q, self._last = key, out
        return out


def state_document(
    snapshot: ControllerSnapshot, tick: TickStats, ports: Ports, tick_count: int | None = None
) -> dict[str, Any]:
    """``GET /api/state``'s document: the snapshot's own document
    (:func:`~pymotoros.runtime.snapshot_document.document_encoder` of its type), then
    the loop's ``tick`` and the listening ``ports``; ``tick_count``, when given,
    replaces ``tick.count`` (the feed's percentiles are refreshed less often than the
    count advances)."""
    doc = document_encoder(type(snapshot))(snapshot)
    late = tick.lateness_ms
    doc["tick"] = {
        "period_ms": tick.period_ms,
        "count": tick.count if tick_count is None else tick_count,
        "overruns": tick.overruns,
        "lateness_ms": {"p50": late.p50, "p99": late.p99, "max": late.max},
    }
    doc["ports"] = {"motion": ports[0], "state": ports[1], "io": ports[2]}
    return doc


def encode(doc: dict[str, Any]) -> str:
    """The document as compact JSON text: the same keys in the same order and the same
    floats (shortest round-trip form) as ``json.dumps(doc, separators=(",", ":"))``, a
    test holds them equal once parsed; only an exponent is spelt shorter (``1e-6`` for
    ``1e-06``). orjson's encoder is compiled: the stdlib's took ~0.13 ms per document on
    the simulator's busy loop, the feed's second cost after the controller's snapshot.
    A non-finite float would be written ``null`` instead of the stdlib's ``NaN`` (which a
    browser's ``JSON.parse`` refuses); the document holds none."""
    return orjson.dumps(doc).decode()


def errors_document(snapshot: ControllerSnapshot) -> list[dict[str, Any]]:
    """The operator errors (not alarms) with code, subcode and text, as the pendant lists
    them: the alarms' shape, from the same declaration."""
    encode = document_encoder(AlarmInfo)
    return [encode(e) for e in snapshot.errors]
