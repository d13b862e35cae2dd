"""What a replay found: per request the reply compared with the recorded one
(:class:`ReplyDiff`), the reply delays (:class:`RequestTiming`), the final positions
(:class:`PositionDiff`), all in one :class:`ReplayResult`. See :mod:`pymotoros.client.replay`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Final

from pymotoros.protocol.constants import (
    MotionCommand,
    MsgType,
)
from pymotoros.protocol.framing import Frame
from pymotoros.protocol.messages import (
    MotoMotionCtrl,
    WireMessage,
)

DEFAULT_TIMING_TOLERANCE_S: Final = 0.05
"""Reply delays further apart than this are listed: MotoROS answers a motion request
within a few 4 ms ticks, START_TRAJ_MODE within its servo-on time; 50 ms is well above
the jitter of a real-time twin on a loaded machine, well below a servo-on."""


# --------------------------------------------------------------------------- summaries


def type_name(msg_type: int) -> str:
    try:
        return MsgType(msg_type).name
    except ValueError:
        return str(msg_type)


def reply_summary(message: WireMessage | None, frame: Frame | None = None) -> dict[str, Any]:
    """What is compared of a reply: ``{"type", "result", "subcode", "value"}`` (None where
    the message has no such field); ``{"type": None, …}`` for no reply at all."""
    if message is None and frame is None:
        return {"type": None, "result": None, "subcode": None, "value": None}
    msg_type = frame.msg_type if frame is not None else getattr(message, "MSG_TYPE", 0)
    result = getattr(message, "result", getattr(message, "result_code", None))
    return {
        "type": type_name(msg_type),
        "result": result,
        "subcode": getattr(message, "subcode", None),
        "value": getattr(message, "value", None),
    }


def is_queue_count(request: WireMessage | None) -> bool:
    return isinstance(request, MotoMotionCtrl) and request.command == MotionCommand.CHECK_QUEUE_CNT


def compared(summary: Mapping[str, Any], request: WireMessage | None) -> dict[str, Any]:
    """The fields compared: the queue count of CHECK_QUEUE_CNT is timing, not a verdict."""
    out = dict(summary)
    if is_queue_count(request):
        out["subcode"] = None
    return out


# --------------------------------------------------------------------------- results


@dataclass(frozen=True, slots=True)
class ReplyDiff:
    """A request whose replayed reply differs from the recorded one."""

    request: int
    """Its number: requests are numbered 1, 2, … in the order the client sent them."""
    connection: int
    port: str
    offset: float
    """Recorded time of the request, s from the recording's start."""
    request_type: str
    sequence: int | None
    command: str | None
    recorded: Mapping[str, Any]
    replayed: Mapping[str, Any]

    def as_json(self) -> dict[str, Any]:
        return {
            "request": self.request,
            "connection": self.connection,
            "port": self.port,
            "offset_s": self.offset,
            "request_type": self.request_type,
            "sequence": self.sequence,
            "command": self.command,
            "recorded": dict(self.recorded),
            "replayed": dict(self.replayed),
        }


@dataclass(frozen=True, slots=True)
class RequestTiming:
    """Reply delay of one request, recorded and replayed (s; None: no reply)."""

    request: int
    port: str
    request_type: str
    recorded_delay: float | None
    replayed_delay: float | None
    recorded_attempts: int
    replayed_attempts: int

    @property
    def difference(self) -> float | None:
        if self.recorded_delay is None or self.replayed_delay is None:
            return None
        return self.replayed_delay - self.recorded_delay

    def as_json(self) -> dict[str, Any]:
        return {
            "request": self.request,
            "port": self.port,
            "request_type": self.request_type,
            "recorded_delay_s": self.recorded_delay,
            "replayed_delay_s": self.replayed_delay,
            "recorded_attempts": self.recorded_attempts,
            "replayed_attempts": self.replayed_attempts,
        }


@dataclass(frozen=True, slots=True)
class PositionDiff:
    """One group's final feedback positions, recorded and replayed."""

    group: int
    recorded: tuple[float, ...] | None
    replayed: tuple[float, ...] | None
    tolerance: tuple[float, ...]

    @property
    def matches(self) -> bool:
        if self.recorded is None or self.replayed is None:
            return self.recorded is None and self.replayed is None
        return all(
            abs(a - b) <= tol
            for a, b, tol in zip(self.recorded, self.replayed, self.tolerance, strict=False)
        )

    def as_json(self) -> dict[str, Any]:
        return {
            "group": self.group,
            "recorded": None if self.recorded is None else list(self.recorded),
            "replayed": None if self.replayed is None else list(self.replayed),
            "tolerance": list(self.tolerance),
            "match": self.matches,
        }


@dataclass(frozen=True, slots=True)
class ReplayResult:
    """The diff between a recording and its replay."""

    requests: int
    connections: int
    recorded_duration: float
    replayed_duration: float
    differences: tuple[ReplyDiff, ...]
    timings: tuple[RequestTiming, ...]
    timing_tolerance: float
    positions: tuple[PositionDiff, ...]
    settled: bool | None
    """The replayed robot stood still when the final positions were taken (None: not
    waited for, the recording ended in motion or without a state connection)."""

    @property
    def slow_or_fast(self) -> tuple[RequestTiming, ...]:
        """Requests whose reply delay differs by more than the tolerance."""
        return tuple(
            t
            for t in self.timings
            if t.difference is not None and abs(t.difference) > self.timing_tolerance
        )

    @property
    def matches(self) -> bool:
        """Every reply as recorded and every final position within its tolerance."""
        return not self.differences and all(p.matches for p in self.positions)

    def as_json(self) -> dict[str, Any]:
        return {
            "match": self.matches,
            "requests": self.requests,
            "connections": self.connections,
            "recorded_duration_s": self.recorded_duration,
            "replayed_duration_s": self.replayed_duration,
            "differences": [d.as_json() for d in self.differences],
            "timing": {
                "tolerance_s": self.timing_tolerance,
                "outside_tolerance": [t.request for t in self.slow_or_fast],
                "requests": [t.as_json() for t in self.timings],
            },
            "final_positions": [p.as_json() for p in self.positions],
            "settled": self.settled,
        }
