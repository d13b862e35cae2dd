"""Client lint: what a client did that a real controller answers differently, or that
works only by luck (issue 31).

The twin sees every byte a client sends, so it can say what no robot, simulator or
driver says: "your client sends fragmented messages", "your stream starved the queue
mid-trajectory". :class:`ClientLint` keeps those observations as findings, one per
(code, connection), counted, with the controller time of the first one. Each code's
reference section, sentence and remedy are declared once, in :data:`RULES`.

Pure domain: no sockets, no clock. The servers (``pymotoros.runtime``) and the tick
report what they see with the controller time passed in; the stateful checks
(sequence numbers after BUSY, a queue that ran empty while the last point moved, a
motion connection opened over queued increments) live here so that they are tested
without a network. Findings are recorded whatever the fidelity setting: ``safe``
forgives what the robot would not, and the lint says so.

Memory is bounded: at most :data:`MAX_FINDINGS` distinct (code, connection) pairs are
kept (a fuzzer opening thousands of connections adds its later ones to one
:data:`OTHER_CONNECTIONS` entry per code), and the per-group sequence state is capped.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

from pymotoros.protocol.constants import ResultCode

__all__ = [
    "MAX_FINDINGS",
    "OTHER_CONNECTIONS",
    "RULES",
    "ClientLint",
    "Finding",
    "LintCode",
    "LintRule",
    "ResumedMotion",
    "format_findings",
]


class LintCode(enum.StrEnum):
    """What a finding is about (the ``code`` of ``GET /api/lint``)."""

    FRAGMENTED_MESSAGE = "fragmented-message"
    LENGTH_MISMATCH = "length-mismatch"
    UNKNOWN_COMMAND = "unknown-command"
    STALE_REPLY = "stale-reply"
    QUEUE_STARVED = "queue-starved"
    BUSY_POINT_SKIPPED = "busy-point-skipped"
    SEQUENCE_NOT_CONSECUTIVE = "sequence-not-consecutive"
    MOTION_WITHOUT_STATE = "motion-without-state"
    RECONNECT_RESUMED_MOTION = "reconnect-resumed-motion"


@dataclass(frozen=True, slots=True)
class LintRule:
    """What one code means: where the reference says it, what happened, what to change."""

    reference: str
    """Section of ``shared/reference/motoros-1.9.12.md``."""
    text: str
    remedy: str


RULES: Final[dict[LintCode, LintRule]] = {
    LintCode.FRAGMENTED_MESSAGE: LintRule(
        "§1.5",
        "A message arrived in more than one TCP read. MotoROS does not reassemble: it "
        "answers the first piece INVALID/3001 and parses the rest as a new message "
        "(usually 3003).",
        "Send each message with one write (one send() of the whole frame, prefix "
        "included), with TCP_NODELAY set, and wait for its reply before the next.",
    ),
    LintCode.LENGTH_MISMATCH: LintRule(
        "§1.1",
        "The prefix length disagrees with the size of the message type. MotoROS never "
        "reads the prefix: it sizes a message by its type, so the bytes after the "
        "expected size become the next message.",
        "Set the prefix to 12 + the body size of the type (§1.3), e.g. 148 for "
        "JOINT_TRAJ_PT_FULL and 64 for MOTO_MOTION_CTRL.",
    ),
    LintCode.UNKNOWN_COMMAND: LintRule(
        "§3.1",
        "A MOTO_MOTION_CTRL command MotoROS does not know. It builds no reply for it "
        "and sends its previous reply again.",
        "Send only the commands of §3.1 (CHECK_MOTION_READY, CHECK_QUEUE_CNT, "
        "STOP_MOTION, START_SERVOS, STOP_SERVOS, RESET_ALARM, START_TRAJ_MODE, "
        "STOP_TRAJ_MODE, DISCONNECT).",
    ),
    LintCode.STALE_REPLY: LintRule(
        "§3.1, §3.5",
        "A request MotoROS answers with its previous reply (an unknown command, or a "
        "JOINT_TRAJ_PT_FULL_EX with numberOfValidGroups <= 0): a stale SUCCESS can look "
        "like an acceptance.",
        "Never send such a request; check that each reply echoes the sequence and "
        "command of the request it answers.",
    ),
    LintCode.QUEUE_STARVED: LintRule(
        "§5.6",
        "A group's increment queue ran empty while the last point it executed had a "
        "non-zero velocity: the trajectory was not finished, and a robot stops abruptly.",
        "Stream points ahead of the motion (the queue holds 200 increments, 0.8 s at "
        "4 ms) and end every trajectory with a point of zero velocity.",
    ),
    LintCode.BUSY_POINT_SKIPPED: LintRule(
        "§3.4",
        "After BUSY for a point, the next point accepted was another one: the BUSY "
        "point was never executed.",
        "On BUSY (result 1) send the same point again, same sequence, until it is "
        "accepted; never advance on BUSY.",
    ),
    LintCode.SEQUENCE_NOT_CONSECUTIVE: LintRule(
        "§3.4",
        "Accepted points were not numbered 0, 1, 2 ... MotoROS accepts any positive "
        "sequence without checking continuity, so a lost or repeated point goes "
        "unnoticed.",
        "Start each trajectory at sequence 0 and number its points consecutively; "
        "resend only after BUSY.",
    ),
    LintCode.MOTION_WITHOUT_STATE: LintRule(
        "§2.3",
        "Trajectory points were streamed while no state connection was open: nobody "
        "watched the robot move (position, alarms, motion-possible).",
        "Connect to the state port (50241) before streaming, and stop streaming when "
        "its stream stalls.",
    ),
    LintCode.RECONNECT_RESUMED_MOTION: LintRule(
        "§2.2",
        "A motion connection was opened while increments queued by a closed one were "
        "still in the queues, and let them run. MotoROS keeps them, and the new "
        "connection's IncMove task resumes the old motion as soon as anybody connects "
        "(a connection whose first request is STOP_MOTION is not reported; in fidelity "
        "safe the twin cleared them at the close, but a robot would have resumed them).",
        "After a reconnect send STOP_MOTION at once and wait for the robot to rest "
        "before planning from its feedback.",
    ),
}
"""Each code's reference section, sentence and remedy, declared once."""

MAX_FINDINGS: Final = 256
"""Distinct (code, connection) findings kept; later connections share one entry per code."""

OTHER_CONNECTIONS: Final = "(other connections)"
"""The connection of the entry that counts findings beyond :data:`MAX_FINDINGS`."""

MAX_TRACKED_GROUPS: Final = 64
"""Per-group sequence states kept before they are all forgotten (only a fuzzer's BUSY or
accepted points name more groups than a controller has: at most 8 on a DX200)."""


@dataclass(frozen=True, slots=True)
class Finding:
    """One code seen on one connection: how often, since when, and what to do."""

    code: LintCode
    count: int
    first_s: float
    """Controller time (s) of the first occurrence."""
    connection: str
    """The client, "host:port"."""
    reference: str
    text: str
    remedy: str

    def as_dict(self) -> dict[str, object]:
        """The JSON object of ``GET /api/lint`` and ``--lint-report``."""
        return {
            "code": str(self.code),
            "count": self.count,
            "first_s": self.first_s,
            "connection": self.connection,
            "reference": self.reference,
            "text": self.text,
            "remedy": self.remedy,
        }


@dataclass(frozen=True, slots=True)
class ResumedMotion:
    """What a new motion connection finds of the increments a closed one left queued
    (§2.2): the controller's ``motion_connected()`` answer, None when there were none."""

    cleared_s: float | None = None
    """None: the queues were kept and run now (fidelity exact, as MotoROS 1.9.12).
    Fidelity safe: the twin cleared them at the close; a robot would have kept them and
    would run them now, for this many seconds (the fullest group's queue)."""


@dataclass(frozen=True, slots=True)
class _Resume:
    """A motion connection opened over a closed one's queued increments that has not
    yet shown what it does about them."""

    connection: str
    opened_s: float
    """Controller time it opened: the finding's ``first_s``."""
    ends_s: float | None
    """Fidelity safe: when the cleared increments would have run out on a robot (the
    twin's queues are empty, so the tick watches this time instead). None in exact."""


@dataclass(slots=True)
class _Entry:
    count: int
    first_s: float
    detail: str


@dataclass(slots=True)
class _Sequence:
    """What one group has had accepted, and what is owed after BUSY. Per group, not per
    connection, as the controller's own state is: a client that reconnects and carries
    on with the next point (``motoman_driver`` does) continues the same numbering."""

    last: int | None = None
    busy: int | None = None


class ClientLint:
    """The findings of one controller, and the small state its checks need."""

    def __init__(self, capacity: int = MAX_FINDINGS) -> None:
        if capacity < 1:
            raise ValueError(f"the lint needs room for at least one finding, got {capacity}")
        self._capacity = capacity
        self._entries: dict[tuple[LintCode, str], _Entry] = {}
        self._sequences: dict[int, _Sequence] = {}
        self._moving: dict[int, str] = {}
        """Groups whose last accepted point had a non-zero velocity -> its connection."""
        self.state_clients = 0
        """Open state connections (the state server reports them through the controller)."""
        self._resumed: _Resume | None = None
        """A motion connection that opened over a closed one's queued increments and has
        not yet shown what it does about them."""

    # ----------------------------------------------------------- findings

    def record(self, code: LintCode, connection: str, now_s: float, detail: str = "") -> None:
        """Count one occurrence of ``code`` on ``connection`` at controller time ``now_s``;
        ``detail`` (the first occurrence's) is added to the finding's text."""
        key = (code, connection)
        entry = self._entries.get(key)
        if entry is None and len(self._entries) >= self._capacity:
            key = (code, OTHER_CONNECTIONS)
            entry = self._entries.get(key)
        if entry is None:
            self._entries[key] = _Entry(1, now_s, detail)
        else:
            entry.count += 1

    def findings(self) -> list[Finding]:
        """Every finding, in the order first seen."""
        out = []
        for (code, connection), entry in self._entries.items():
            rule = RULES[code]
            text = f"{rule.text} First: {entry.detail}." if entry.detail else rule.text
            out.append(
                Finding(
                    code,
                    entry.count,
                    entry.first_s,
                    connection,
                    rule.reference,
                    text,
                    rule.remedy,
                )
            )
        return out

    def document(self) -> dict[str, Any]:
        """``{"findings": [...]}``: the answer of ``GET /api/lint``, ``--lint-report`` and
        ``pymotoros lint --json``."""
        return {"findings": [f.as_dict() for f in self.findings()]}

    def clear(self) -> None:
        """Forget every finding (the checks' state is kept: a stream in progress goes on)."""
        self._entries.clear()

    def __len__(self) -> int:
        return len(self._entries)

    # ----------------------------------------------------------- checks

    def point_answered(
        self,
        connection: str,
        groups: Sequence[tuple[int, bool]],
        sequence: int,
        result: int,
        now_s: float,
    ) -> None:
        """A trajectory point (type 14 or 2016) was answered ``result``; ``groups``: each
        group it carries, and whether its velocity there is non-zero (then the queue must
        not run dry after it). Checks motion-without-state, busy-point-skipped and
        sequence-not-consecutive; remembers the moving groups for :meth:`queue_ran_empty`.
        """
        if self.state_clients <= 0:
            self.record(LintCode.MOTION_WITHOUT_STATE, connection, now_s, f"point {sequence}")
        if result == ResultCode.BUSY:
            for group, _ in groups:
                state = self._sequence(group)
                if state.busy is not None and state.busy != sequence:
                    self.record(
                        LintCode.BUSY_POINT_SKIPPED,
                        connection,
                        now_s,
                        f"group {group}: BUSY for point {state.busy}, then point {sequence}",
                    )
                state.busy = sequence
            return
        if result != ResultCode.SUCCESS:
            return
        for group, moving in groups:
            state = self._sequence(group)
            busy, state.busy = state.busy, None
            if sequence == 0:  # a new trajectory: whatever was owed is abandoned
                state.last = 0
            elif busy is not None and busy != sequence:
                self.record(
                    LintCode.BUSY_POINT_SKIPPED,
                    connection,
                    now_s,
                    f"group {group}: BUSY for point {busy}, then point {sequence} accepted",
                )
                state.last = sequence
            else:
                expected = 0 if state.last is None else state.last + 1
                if sequence != expected:
                    self.record(
                        LintCode.SEQUENCE_NOT_CONSECUTIVE,
                        connection,
                        now_s,
                        f"group {group}: point {sequence} accepted where {expected} was next",
                    )
                state.last = sequence
            if moving:
                self._moving[group] = connection
            else:
                self._moving.pop(group, None)

    def motion_reset(self) -> None:
        """A MOTO_MOTION_CTRL that ends the motion (STOP_MOTION, START_TRAJ_MODE …) or a
        queue clear: a point owed after BUSY is no longer owed, the next trajectory
        starts at 0, and an emptied queue is not a starved one."""
        self._sequences.clear()
        self._moving.clear()

    @property
    def watching_queues(self) -> bool:
        """Some group's last accepted point moves: the tick must watch its queue."""
        return bool(self._moving)

    def moving_groups(self) -> tuple[int, ...]:
        return tuple(self._moving)

    def queue_ran_empty(self, group: int, now_s: float) -> None:
        """IncMove emptied ``group``'s queue (nothing pending) after a moving point."""
        connection = self._moving.pop(group, None)
        if connection is not None:
            self.record(
                LintCode.QUEUE_STARVED,
                connection,
                now_s,
                f"group {group} at {now_s:.3f} s",
            )

    def motion_opened(
        self, connection: str, now_s: float, *, queued: bool, cleared_s: float | None = None
    ) -> None:
        """A motion connection took its slot; ``queued``: increments a closed connection
        left queued resume now, or would on a robot (the controller's
        ``motion_connected()``); ``cleared_s``: fidelity safe, the twin cleared them at the
        close, and a robot would run them for this long (:class:`ResumedMotion`).

        Not a finding yet: a client that sends STOP_MOTION as its first request does what
        a robot needs (docs/client.md), and its reconnect works by design, not by luck.
        The finding is recorded, dated when the connection opened, when the connection
        lets the old motion run instead: its first request is anything else
        (:meth:`motion_request`), or it closes without a request (:meth:`motion_closed`).
        Not when the old motion ran out first: over TCP a connection lost in the last
        ticks of a move would give a client that stops first a finding. In safe the same
        rule applies to what a robot would have done, and the text says the twin cleared
        the queues.
        """
        self._settle_resume("another motion connection opened before it sent anything")
        if not queued:
            self._resumed = None
            return
        ends_s = None if cleared_s is None else now_s + cleared_s
        self._resumed = _Resume(connection, now_s, ends_s)

    @property
    def resume_pending(self) -> bool:
        """A motion connection opened over resumed increments and has sent nothing yet."""
        return self._resumed is not None

    def motion_request(self, connection: str, *, stops: bool, what: str) -> None:
        """``connection`` sent a request on the motion port; ``stops``: it is STOP_MOTION
        (``what`` names it otherwise). Only the first after a resume matters."""
        pending = self._resumed
        if pending is None or pending.connection != connection:
            return
        self._resumed = None
        if not stops:
            self._record_resumed(pending, f"its first request was {what}, not STOP_MOTION")

    def motion_closed(self, connection: str) -> None:
        """``connection`` left the motion port."""
        if self._resumed is not None and self._resumed.connection == connection:
            self._settle_resume("it closed without sending STOP_MOTION")

    def _settle_resume(self, why: str) -> None:
        pending, self._resumed = self._resumed, None
        if pending is not None:
            self._record_resumed(pending, why)

    def _record_resumed(self, pending: _Resume, why: str) -> None:
        if pending.ends_s is None:
            what = "increments of a closed connection were still queued and ran"
        else:
            what = (
                "increments of a closed connection were queued when it closed; fidelity "
                "safe cleared them, but a robot would have kept them and resumed them "
                "under this connection"
            )
        self.record(
            LintCode.RECONNECT_RESUMED_MOTION,
            pending.connection,
            pending.opened_s,
            f"{what}: {why}",
        )

    def _sequence(self, group: int) -> _Sequence:
        state = self._sequences.get(group)
        if state is None:
            if len(self._sequences) >= MAX_TRACKED_GROUPS:
                self._sequences.clear()
            state = self._sequences[group] = _Sequence()
        return state


def format_findings(findings: Sequence[Finding]) -> str:
    """A readable table: one block per finding, the remedy under what happened."""
    if not findings:
        return "no client lint findings"
    lines = [f"{len(findings)} client lint finding(s):"]
    for f in findings:
        lines.append(
            f"  {f.code}  x{f.count}  first at {f.first_s:.3f} s  on {f.connection}  "
            f"({f.reference})"
        )
        lines.append(f"      {f.text}")
        lines.append(f"      fix: {f.remedy}")
    return "\n".join(lines)
