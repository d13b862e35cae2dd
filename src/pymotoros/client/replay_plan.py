"""Which recorded requests a replay sends, and how it waits: each request paired with
its recorded replies (:class:`ReplayStep`), the BUSY / NOT_READY answers that make one
request of several identical sends (:func:`retried`), and the think time kept before each
(:func:`replay_plan`). See :mod:`pymotoros.client.replay`.
"""

from __future__ import annotations

import dataclasses
import statistics
from dataclasses import dataclass
from typing import Final

from pymotoros.client.recording import (
    Direction,
    RecordedConnection,
    RecordedMessage,
    Recording,
)
from pymotoros.protocol.constants import (
    CommType,
    Port,
    ResultCode,
    reply_result,
)
from pymotoros.protocol.messages import (
    MotoMotionReply,
    WireMessage,
)

RETRY_WINDOW_MIN_S: Final = 10.0
"""How long the replay resends a point answered BUSY (or a poll answered NOT_READY) at
least: the client's own BUSY timeout (pymotoros.client.streaming)."""


RETRY_WINDOW_FACTOR: Final = 2.0
"""… or this many times as long as the recorded client kept resending, if longer."""


DEFAULT_RETRY_GAP_S: Final = 0.002
"""Resend gap when the recording shows none for a request: the client's longest BUSY
back-off (pymotoros.client.streaming)."""


RETRIED: Final = frozenset({int(ResultCode.BUSY), int(ResultCode.NOT_READY)})
"""Results after which a client resends the same request (a point, a readiness poll)."""


def retried(message: WireMessage | None) -> int | None:
    """The result, if it is one after which a client resends the same request."""
    if isinstance(message, MotoMotionReply):
        result = reply_result(message.result, message.subcode)
        return result if result in RETRIED else None
    return None


# --------------------------------------------------------------------------- the plan


@dataclass(frozen=True, slots=True)
class ReplayStep:
    """One logical request of the recording: its attempts (resends) and final reply."""

    number: int
    conn: RecordedConnection
    attempts: tuple[RecordedMessage, ...]
    final_reply: RecordedMessage | None
    expects_reply: bool
    think: float
    """Recorded gap between the previous step's reply (or the connection's opening) and
    this step's first send."""
    retry_gap: float
    polled: bool
    """The recorded client resent it after a NOT_READY (a readiness poll)."""

    @property
    def first(self) -> RecordedMessage:
        return self.attempts[0]

    @property
    def recorded_delay(self) -> float | None:
        if self.final_reply is None:
            return None
        return self.final_reply.time - self.attempts[-1].time

    @property
    def retry_window(self) -> float:
        span = self.attempts[-1].time - self.attempts[0].time
        return max(RETRY_WINDOW_MIN_S, RETRY_WINDOW_FACTOR * span)


def request_pairs(
    conn: RecordedConnection,
) -> list[tuple[RecordedMessage, RecordedMessage | None, bool]]:
    """(request, its reply or None, reply awaited) in order: replies answer the oldest
    unanswered request (MotoROS answers in order)."""
    pending: list[int] = []
    out: list[tuple[RecordedMessage, RecordedMessage | None, bool]] = []
    for message in conn.messages:
        if message.direction is Direction.TO_SERVER:
            # A motion-port message sent as a SERVICE_REPLY gets no answer (§1.5).
            expects = not (
                conn.kind is Port.MOTION and message.frame.comm_type == CommType.SERVICE_REPLY
            )
            out.append((message, None, expects))
            if expects:
                pending.append(len(out) - 1)
        elif not message.is_topic and pending:
            index = pending.pop(0)
            request, _, expects = out[index]
            out[index] = (request, message, expects)
    return out


def replay_plan(recording: Recording) -> dict[int, list[ReplayStep]]:
    """The steps of each motion and IO connection (index → steps)."""
    plans: dict[int, list[ReplayStep]] = {}
    for conn in recording.connections:
        if conn.kind is Port.STATE or not conn.sent():
            continue
        pairs = request_pairs(conn)
        steps: list[ReplayStep] = []
        previous_done = recording.start + conn.opened
        i = 0
        while i < len(pairs):
            group = [pairs[i]]
            # a resend: the same bytes again after a BUSY or NOT_READY reply
            while (
                i + len(group) < len(pairs)
                and group[-1][1] is not None
                and retried(group[-1][1].message) is not None
                and pairs[i + len(group)][0].frame == group[-1][0].frame
            ):
                group.append(pairs[i + len(group)])
            i += len(group)
            attempts = tuple(request for request, _, _ in group)
            final = group[-1][1]
            gaps = [
                later.time - reply.time
                for (_, reply, _), later in zip(group, attempts[1:], strict=False)
                if reply is not None
            ]
            polled = any(
                retried(reply.message) == ResultCode.NOT_READY
                for _, reply, _ in group[:-1]
                if reply is not None
            )
            steps.append(
                ReplayStep(
                    number=0,  # set below
                    conn=conn,
                    attempts=attempts,
                    final_reply=final,
                    expects_reply=group[-1][2],
                    think=max(0.0, attempts[0].time - previous_done),
                    retry_gap=statistics.fmean(gaps) if gaps else DEFAULT_RETRY_GAP_S,
                    polled=polled,
                )
            )
            previous_done = final.time if final is not None else attempts[-1].time
        plans[conn.index] = steps
    # numbered in the order the client sent them, across connections
    ordered = sorted((s for steps in plans.values() for s in steps), key=lambda s: s.first.time)
    numbers = {id(s): n for n, s in enumerate(ordered, start=1)}
    return {
        index: [dataclasses.replace(s, number=numbers[id(s)]) for s in steps]
        for index, steps in plans.items()
    }
