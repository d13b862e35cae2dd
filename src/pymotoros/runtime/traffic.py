"""What a MotoROS port served, counted in plain ints on the hot path.

Each framed server (motion, IO) owns one :class:`Traffic`. Counting a request or a reply
is one dict update; nothing is formatted or labelled until somebody scrapes
``GET /metrics`` (:mod:`pymotoros.runtime.metrics` reads these dicts then), so a twin
nobody monitors pays a few hundred nanoseconds per message and no more.
"""

from __future__ import annotations

from typing import Final

from pymotoros.protocol.constants import MotionCommand, MsgType
from pymotoros.protocol.messages import Message, MotoMotionReply

__all__ = ["OTHER", "Traffic"]

OTHER: Final = -1
"""The key every message type or command outside the protocol's own is counted under: a
client sending random types (a fuzzer, a wrong port) must not grow the counters, nor the
labels ``GET /metrics`` exports, without bound (one key per distinct value, before)."""

_KNOWN_TYPES: Final = frozenset(int(t) for t in MsgType)
_KNOWN_SUBJECTS: Final = _KNOWN_TYPES | frozenset(int(c) for c in MotionCommand)


class Traffic:
    """Requests by message type; replies by (subject, result); refusals by (result, subcode).

    A reply's *subject* is what it answers: the MOTION_CTRL command or request type a
    MOTO_MOTION_REPLY echoes (§1.6), else the reply's own message type. Results are
    MotoROS's (0 SUCCESS, 1 BUSY, 2 FAILURE, 3 INVALID, 4 ALARM, 5 NOT_READY) on the
    motion port, the IO result code on the IO port.
    """

    __slots__ = ("refusals", "replies", "requests")

    def __init__(self) -> None:
        self.requests: dict[int, int] = {}
        self.replies: dict[tuple[int, int], int] = {}
        self.refusals: dict[tuple[int, int], int] = {}

    def request(self, msg_type: int) -> None:
        if msg_type not in _KNOWN_TYPES:
            msg_type = OTHER
        self.requests[msg_type] = self.requests.get(msg_type, 0) + 1

    def reply(self, message: Message) -> None:
        if type(message) is MotoMotionReply:  # the motion port's every reply: kept lean
            key = message[2:4]  # (command, result): the tuple's own fields, no properties
            if key[0] not in _KNOWN_SUBJECTS:  # a command the client made up, echoed
                key = (OTHER, key[1])
            if key[1]:
                refusal = message[3:5]  # (result, subcode)
                self.refusals[refusal] = self.refusals.get(refusal, 0) + 1
        else:
            code = getattr(message, "result_code", None)
            result = int(getattr(message, "result", 0) if code is None else code)
            key = (int(getattr(type(message), "MSG_TYPE", 0)), result)
            if key[1]:
                refusal = (key[1], int(getattr(message, "subcode", 0)))
                self.refusals[refusal] = self.refusals.get(refusal, 0) + 1
        self.replies[key] = self.replies.get(key, 0) + 1
