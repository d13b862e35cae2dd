"""``pymotoros lint RECORDING``, and ``pymotoros sim --lint-report FILE``: client lint
outside the twin's control API (issue 31).

``pymotoros lint`` reads a session recording (the pcapng of ``--record``, or a capture
of a real session: :mod:`pymotoros.client.recording`) and applies the checks of
:mod:`pymotoros.controller.lint` to what the client sent and what it was answered:

- fragmented-message: a request completed by a later TCP segment than the one it started
  in (the same test the twin makes on its reads);
- length-mismatch, unknown-command, stale-reply: from each request's bytes;
- busy-point-skipped, sequence-not-consecutive, motion-without-state: from each point
  and the reply it got, and the state connections open at that moment;
- queue-starved and reconnect-resumed-motion are *estimated*, as a recording holds no
  queue: a group's queue runs until the trajectory time of its last accepted point,
  counted from its sequence-0 point; a moving point not followed by another before that
  time starved it, and a motion connection opened before it while the previous one had
  closed would, on a robot, resume those increments.

Times (``first_s``) are seconds since the start of the recording. Exit codes: 0 no
finding, 1 findings, 2 usage error or unreadable recording.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import click

from pymotoros.cli.options import InputFile, json_option
from pymotoros.client.recording import (
    Direction,
    RecordedConnection,
    RecordedMessage,
    Recording,
    RecordingError,
    read_recording,
)
from pymotoros.controller.lint import ClientLint, LintCode, format_findings
from pymotoros.errors import RemoteProtocolError
from pymotoros.protocol.constants import MotionCommand, Port
from pymotoros.protocol.framing import FrameDecoder
from pymotoros.protocol.messages import (
    JointTrajPtFull,
    MotoJointTrajPtFullEx,
    MotoMotionCtrl,
    MotoMotionReply,
)
from pymotoros.protocol.sizes import check_request, is_length_mismatch
from pymotoros.runtime.motion_server import KNOWN_COMMANDS, QUIET_COMMANDS

__all__ = ["lint", "lint_recording", "write_lint_report"]

EXIT_CLEAN: Final = 0
EXIT_FINDINGS: Final = 1
EXIT_USAGE: Final = 2


# --------------------------------------------------------------------------- sim's report


def write_lint_report(path: Path, cells: Sequence[tuple[str | None, ClientLint]]) -> None:
    """``--lint-report``: ``{"findings": [...]}`` of the twin (several cells: each finding
    also names its ``cell``), written when the twin stops."""
    findings: list[dict[str, Any]] = []
    for name, lint in cells:
        for finding in lint.findings():
            entry = finding.as_dict()
            if name is not None and len(cells) > 1:
                entry["cell"] = name
            findings.append(entry)
    path.write_text(json.dumps({"findings": findings}, indent=2) + "\n", encoding="utf-8")


# --------------------------------------------------------------------------- recordings


@dataclass(slots=True)
class _Trajectory:
    """One group's trajectory as the recording shows it (for the queue estimates)."""

    start_s: float | None = None
    """Recording time at which the trajectory's time 0 passes on the robot: set when the
    first point after sequence 0 is accepted (the motion starts then), and again when a
    point comes after the queue ran dry (the motion starts again from it)."""
    last_time: float = 0.0
    """Trajectory time of the last accepted point."""
    moving: bool = False
    """The last accepted point has a non-zero velocity."""

    @property
    def queue_end_s(self) -> float | None:
        """When the queue runs out: the last accepted point's time on the robot's clock."""
        return None if self.start_s is None else self.start_s + self.last_time


@dataclass(slots=True)
class _Session:
    recording: Recording
    lint: ClientLint = field(default_factory=ClientLint)
    trajectories: dict[int, _Trajectory] = field(default_factory=dict)

    def state_clients_at(self, t: float) -> int:
        return sum(
            1
            for c in self.recording.on(Port.STATE)
            if c.opened <= t and (c.closed is None or t < c.closed)
        )

    def queue_end_s(self) -> float | None:
        ends = [e for t in self.trajectories.values() if (e := t.queue_end_s) is not None]
        return max(ends) if ends else None


def _name(conn: RecordedConnection) -> str:
    return conn.client or f"client:{conn.client_port}"


def _fragments(session: _Session, conn: RecordedConnection) -> None:
    """A request completed by a later segment than the one it began in."""
    if conn.order is None:
        return
    decoder = FrameDecoder(conn.order)
    for chunk in conn.chunks:
        if chunk.direction is not Direction.TO_SERVER:
            continue
        fragmented = decoder.buffered > 0
        decoder.feed(chunk.payload)
        while True:
            try:
                frame = decoder.next_frame()
            except RemoteProtocolError:
                decoder.discard()
                break
            if frame is None:
                break
            if fragmented:
                fragmented = False
                session.lint.record(
                    LintCode.FRAGMENTED_MESSAGE,
                    _name(conn),
                    chunk.offset,
                    f"type {frame.msg_type}",
                )


def _sizes(session: _Session, conn: RecordedConnection, kind: Port) -> None:
    if conn.order is None:
        return
    for m in conn.sent():
        if is_length_mismatch(m.frame, check_request(m.frame, conn.order, kind)):
            session.lint.record(
                LintCode.LENGTH_MISMATCH,
                _name(conn),
                m.offset,
                f"type {m.msg_type}: prefix length {m.frame.size - 4}",
            )


def _pairs(conn: RecordedConnection) -> list[tuple[RecordedMessage, MotoMotionReply | None]]:
    """Each request with the reply that answered it (in order; None: none came)."""
    out: list[tuple[RecordedMessage, MotoMotionReply | None]] = []
    waiting: list[RecordedMessage] = []
    for m in conn.messages:
        if m.direction is Direction.TO_SERVER:
            waiting.append(m)
        elif waiting and not m.is_topic:
            request = waiting.pop(0)
            out.append((request, m.message if isinstance(m.message, MotoMotionReply) else None))
    out.extend((m, None) for m in waiting)
    return out


def _motion(session: _Session, conn: RecordedConnection, previous_closed: float | None) -> None:
    lint, name = session.lint, _name(conn)
    end = session.queue_end_s()
    resumed = (
        previous_closed is not None and end is not None and previous_closed < end > conn.opened
    )
    # as on the twin: a finding once the connection lets the resumed motion run
    lint.motion_opened(name, conn.opened, queued=resumed)
    for request, reply in _pairs(conn):
        msg, t = request.message, request.offset
        if lint.resume_pending:  # what the connection did first about the resumed motion
            _first_request(lint, name, msg)
        if isinstance(msg, MotoMotionCtrl):
            if msg.command not in KNOWN_COMMANDS:
                lint.record(LintCode.UNKNOWN_COMMAND, name, t, f"command {msg.command}")
                lint.record(LintCode.STALE_REPLY, name, t, f"MOTO_MOTION_CTRL {msg.command}")
            elif msg.command not in QUIET_COMMANDS:  # queries reset nothing
                lint.motion_reset()
                session.trajectories.clear()
            continue
        if isinstance(msg, MotoJointTrajPtFullEx) and msg.number_of_valid_groups <= 0:
            lint.record(LintCode.STALE_REPLY, name, t, "FULL_EX with no groups")
            continue
        if isinstance(msg, JointTrajPtFull):
            points = [(msg.group_no, msg.time, any(msg.vel))]
        elif isinstance(msg, MotoJointTrajPtFullEx):
            points = [(g.group_no, g.time, any(g.vel)) for g in msg.groups]
        else:
            continue
        if reply is None:
            continue
        at = request.offset  # the reply follows at once
        lint.state_clients = session.state_clients_at(t)
        lint.point_answered(name, [(g, v) for g, _, v in points], msg.sequence, reply.result, at)
        if reply.result == 0:
            _accepted(session, name, points, msg.sequence, at)
    if lint.resume_pending and conn.closed is not None:  # it closed without a request
        lint.motion_closed(name)


def _first_request(lint: ClientLint, name: str, msg: object) -> None:
    stops = isinstance(msg, MotoMotionCtrl) and msg.command == MotionCommand.STOP_MOTION
    what = f"command {msg.command}" if isinstance(msg, MotoMotionCtrl) else type(msg).__name__
    lint.motion_request(name, stops=stops, what=what)


def _accepted(
    session: _Session,
    name: str,
    points: list[tuple[int, float, bool]],
    sequence: int,
    at: float,
) -> None:
    for group, time, moving in points:
        traj = session.trajectories.setdefault(group, _Trajectory())
        end = traj.queue_end_s
        if end is not None and at > end:  # the queue ran dry before this point came
            if traj.moving:
                session.lint.record(
                    LintCode.QUEUE_STARVED, name, end, f"group {group} (estimated at {end:.3f} s)"
                )
            traj.start_s = None  # the motion starts again from this point
        if sequence == 0:
            traj.start_s = None
        elif traj.start_s is None:  # the segment to this point starts being executed now
            traj.start_s = at - traj.last_time
        traj.last_time, traj.moving = time, moving


def _starved_at_end(session: _Session, name: str) -> None:
    """The last trajectory ran out moving (only if the recording lasted until then)."""
    for group, traj in session.trajectories.items():
        end = traj.queue_end_s
        if traj.moving and end is not None and end <= session.recording.duration:
            session.lint.record(
                LintCode.QUEUE_STARVED, name, end, f"group {group} (estimated at {end:.3f} s)"
            )
    session.trajectories.clear()


def lint_recording(recording: Recording) -> ClientLint:
    """The client lint's findings for a recorded session (see the module's docstring)."""
    session = _Session(recording)
    previous_closed: float | None = None
    last_motion = ""
    for conn in recording.connections:
        if conn.kind in (Port.MOTION, Port.IO):
            _fragments(session, conn)
            _sizes(session, conn, conn.kind)
    for conn in sorted(recording.on(Port.MOTION), key=lambda c: c.opened):
        end = session.queue_end_s()
        if previous_closed is not None and end is not None and end <= conn.opened:
            _starved_at_end(session, last_motion)  # it ran out before this connection
        _motion(session, conn, previous_closed)
        previous_closed, last_motion = conn.closed, _name(conn)
    if last_motion:
        _starved_at_end(session, last_motion)
    return session.lint


# --------------------------------------------------------------------------- the command


@click.command()
@click.argument("recording_path", type=InputFile("session recording (pcapng)"))
@json_option("the findings")
def lint(recording_path: Path, as_json: bool) -> None:
    """Lint a recorded session: what the client did that a real controller answers
    differently, or that works only by luck.

    RECORDING is the pcapng of `--record` (or of `pymotoros sim --record`, or a capture of
    a real session). Exit code 1 when there are findings, 0 when none.
    """
    try:
        recording = read_recording(recording_path)
    except RecordingError as exc:
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_USAGE)
    findings = lint_recording(recording).findings()
    if as_json:
        click.echo(json.dumps({"findings": [f.as_dict() for f in findings]}, indent=2))
    else:
        click.echo(format_findings(findings))
    sys.exit(EXIT_FINDINGS if findings else EXIT_CLEAN)
