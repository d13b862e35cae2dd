"""Replaying the client side of a recorded session against a controller, and the diff.

:func:`replay` takes a :class:`~pymotoros.client.recording.Recording`, opens each
recorded connection again at the time it was opened, sends every message the
client sent, byte for byte, with the original pacing, awaits each reply as the
original client did, reads the state port like it, and compares:

- **replies**: per request, the reply's message type, ``result`` and ``subcode``
  (and the value of an IO or M-register read) against the recorded one;
- **timing**: per request, the reply delay (reply received − request sent), recorded
  and replayed; delays further apart than a tolerance are listed (they do not make
  the replay differ: a real-time twin on a busy machine jitters by milliseconds);
- **final positions**: the last JOINT_FEEDBACK of each group, recorded and replayed
  (the replay's taken once the robot has settled, when the recording ended settled),
  per joint within a tolerance (one encoder pulse, given by the caller).

What the recording cannot dictate. MotoROS answers BUSY when its one pending-point
slot is taken, and a client resends the same point; how many BUSY a point gets
depends on timing, so a run of identical requests answered BUSY (or NOT_READY, a
readiness poll) and then something else is one *request* whose final reply is
compared: the replay resends while it gets BUSY, or the poll's NOT_READY, within a
bounded time. The subcode of a CHECK_QUEUE_CNT reply is the queue's length at that
instant, so it is not compared. ``data`` of a MOTION_REPLY is not compared (MotoROS
leaves it zero).

Pacing: request *k* goes out at its recorded time after the replay's start, but
never sooner after the previous reply than the original client waited after it
(its think time), so a slower controller shifts what follows instead of crowding it.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import statistics
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Final, TypeAlias

from pymotoros.client.recording import (
    Direction,
    RecordedConnection,
    RecordedMessage,
    Recording,
)
from pymotoros.protocol.constants import (
    ByteOrder,
    CommType,
    MotionCommand,
    MsgType,
    Port,
    ResultCode,
    reply_result,
)
from pymotoros.protocol.framing import Frame, FrameDecoder, decode_reply, encode_frame
from pymotoros.protocol.messages import (
    JointFeedback,
    MotoJointFeedbackEx,
    MotoMotionCtrl,
    MotoMotionReply,
    RobotStatus,
    WireMessage,
)

__all__ = [
    "DEFAULT_TIMING_TOLERANCE_S",
    "PositionDiff",
    "ReplayResult",
    "ReplyDiff",
    "RequestTiming",
    "replay",
    "reply_summary",
]

DEFAULT_TIMING_TOLERANCE_S: Final = 0.05
"""Reply delays further apart than this are listed: MotoROS answers a motion request
within a few 4 ms ticks, START_TRAJ_MODE within its servo-on time; 50 ms is well above
the jitter of a real-time twin on a loaded machine, well below a servo-on."""

REPLY_TIMEOUT_S: Final = 5.0
"""A request the controller does not answer within this is reported as unanswered
(the client's own request timeout, pymotoros.client.connection)."""

CONNECT_TIMEOUT_S: Final = 5.0
"""Connecting to a port of the target: as the client does."""

RETRY_WINDOW_MIN_S: Final = 10.0
"""How long the replay resends a point answered BUSY (or a poll answered NOT_READY) at
least: the client's own BUSY timeout (pymotoros.client.streaming)."""

RETRY_WINDOW_FACTOR: Final = 2.0
"""… or this many times as long as the recorded client kept resending, if longer."""

DEFAULT_RETRY_GAP_S: Final = 0.002
"""Resend gap when the recording shows none for a request: the client's longest BUSY
back-off (pymotoros.client.streaming)."""

SETTLE_TIMEOUT_S: Final = 30.0
"""How long after the recorded end the replay waits for the robot to stand still
(ROBOT_STATUS in_motion 0) before it takes the final positions anyway."""

READ_CHUNK: Final = 4096

_RETRIED: Final = frozenset({int(ResultCode.BUSY), int(ResultCode.NOT_READY)})
"""Results after which a client resends the same request (a point, a readiness poll)."""

Connector: TypeAlias = Callable[
    [str, int], Awaitable[tuple[asyncio.StreamReader, asyncio.StreamWriter]]
]


# --------------------------------------------------------------------------- summaries


def _type_name(msg_type: int) -> str:
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
        "type": _type_name(msg_type),
        "result": result,
        "subcode": getattr(message, "subcode", None),
        "value": getattr(message, "value", None),
    }


def _is_queue_count(request: WireMessage | None) -> bool:
    return isinstance(request, MotoMotionCtrl) and request.command == MotionCommand.CHECK_QUEUE_CNT


def _compared(summary: Mapping[str, Any], request: WireMessage | None) -> dict[str, Any]:
    """The fields compared: the queue count of CHECK_QUEUE_CNT is timing, not a verdict."""
    out = dict(summary)
    if _is_queue_count(request):
        out["subcode"] = None
    return out


def _retried(message: WireMessage | None) -> int | None:
    """The result, if it is one after which a client resends the same request."""
    if isinstance(message, MotoMotionReply):
        result = reply_result(message.result, message.subcode)
        return result if result in _RETRIED else None
    return None


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


# --------------------------------------------------------------------------- the plan


@dataclass(frozen=True, slots=True)
class _Step:
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


def _pairs(
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


def _plan(recording: Recording) -> dict[int, list[_Step]]:
    """The steps of each motion and IO connection (index → steps)."""
    plans: dict[int, list[_Step]] = {}
    for conn in recording.connections:
        if conn.kind is Port.STATE or not conn.sent():
            continue
        pairs = _pairs(conn)
        steps: list[_Step] = []
        previous_done = recording.start + conn.opened
        i = 0
        while i < len(pairs):
            group = [pairs[i]]
            # a resend: the same bytes again after a BUSY or NOT_READY reply
            while (
                i + len(group) < len(pairs)
                and group[-1][1] is not None
                and _retried(group[-1][1].message) is not None
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
                _retried(reply.message) == ResultCode.NOT_READY
                for _, reply, _ in group[:-1]
                if reply is not None
            )
            steps.append(
                _Step(
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


# --------------------------------------------------------------------------- replaying


@dataclass
class _Observed:
    """What the replay's state connections said."""

    feedback: dict[int, tuple[float, ...]] = field(default_factory=dict)
    status: RobotStatus | None = None
    still: asyncio.Event = field(default_factory=asyncio.Event)
    watching: bool = False

    def take(self, message: WireMessage) -> None:
        if isinstance(message, JointFeedback):
            self.feedback[message.group_no] = tuple(message.pos)
        elif isinstance(message, MotoJointFeedbackEx):
            for record in message.groups:
                self.feedback[record.group_no] = tuple(record.pos)
        elif isinstance(message, RobotStatus):
            self.status = message
            if self.watching and message.in_motion == 0:
                self.still.set()


@dataclass(frozen=True, slots=True)
class _Outcome:
    step: _Step
    reply: WireMessage | None
    reply_frame: Frame | None
    delay: float | None
    attempts: int


class _Link:
    """One replayed connection: raw writes, and whole frames off a reader task."""

    def __init__(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, order: ByteOrder
    ) -> None:
        self.writer = writer
        self.frames: asyncio.Queue[tuple[float, Frame] | None] = asyncio.Queue()
        self._reader = reader
        self._decoder = FrameDecoder(order)
        self._task = asyncio.create_task(self._read(), name="pymotoros-replay-reader")

    async def _read(self) -> None:
        loop = asyncio.get_running_loop()
        try:
            while data := await self._reader.read(READ_CHUNK):
                now = loop.time()
                self._decoder.feed(data)
                for frame in self._decoder.frames():
                    self.frames.put_nowait((now, frame))
        except OSError:
            pass
        finally:
            self.frames.put_nowait(None)  # the connection is gone

    async def close(self) -> None:
        self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        self.writer.close()
        with contextlib.suppress(OSError, TimeoutError):
            async with asyncio.timeout(CONNECT_TIMEOUT_S):
                await self.writer.wait_closed()


async def _sleep_until(deadline: float) -> None:
    delay = deadline - asyncio.get_running_loop().time()
    if delay > 0:
        await asyncio.sleep(delay)


async def _open(connect: Connector, host: str, port: int, kind: Port, order: ByteOrder) -> _Link:
    try:
        async with asyncio.timeout(CONNECT_TIMEOUT_S):
            reader, writer = await connect(host, port)
    except (OSError, TimeoutError) as exc:
        raise ConnectionError(
            f"replay: cannot connect to the {kind.value} port {host}:{port} ({exc or 'timeout'})"
        ) from None
    return _Link(reader, writer, order)


async def _next_reply(link: _Link) -> tuple[float, Frame] | None:
    """The next frame that is not a topic, None if the connection closed or nothing came."""
    try:
        async with asyncio.timeout(REPLY_TIMEOUT_S):
            while True:
                item = await link.frames.get()
                if item is None:
                    link.frames.put_nowait(None)  # stays closed for later requests
                    return None
                if item[1].comm_type != CommType.TOPIC:
                    return item
    except TimeoutError:
        return None


async def _replay_requests(
    steps: Sequence[_Step],
    conn: RecordedConnection,
    t0: float,
    connect: Connector,
    host: str,
    port: int,
    order: ByteOrder,
    recording_end: float,
) -> list[_Outcome]:
    loop = asyncio.get_running_loop()
    kind = conn.kind or Port.MOTION
    await _sleep_until(t0 + conn.opened)
    link = await _open(connect, host, port, kind, order)
    outcomes: list[_Outcome] = []
    try:
        previous_done = loop.time()
        for step in steps:
            await _sleep_until(max(t0 + step.first.offset, previous_done + step.think))
            data = encode_frame(step.first.frame, order)
            recorded_final = _retried(
                step.final_reply.message if step.final_reply is not None else None
            )
            deadline = loop.time() + step.retry_window
            attempts = 0
            reply: tuple[float, Frame] | None = None
            message: WireMessage | None = None
            sent = loop.time()
            while True:
                sent = loop.time()
                link.writer.write(data)
                attempts += 1
                with contextlib.suppress(OSError):
                    await link.writer.drain()
                if not step.expects_reply:
                    break
                reply = await _next_reply(link)
                if reply is None:
                    message = None
                    break
                message = decode_reply(reply[1], order, kind)
                again = _retried(message)
                if again is None or loop.time() >= deadline:
                    break
                if again == ResultCode.NOT_READY and not step.polled:
                    break  # the recorded client did not poll this: a verdict, not a wait
                if again == recorded_final and attempts >= len(step.attempts):
                    break  # the recorded client gave up here too
                await asyncio.sleep(step.retry_gap)
            delay = None if reply is None else reply[0] - sent
            outcomes.append(
                _Outcome(step, message, None if reply is None else reply[1], delay, attempts)
            )
            previous_done = loop.time() if reply is None else reply[0]
        # as recorded: closed when the client closed it, else when the recording ends
        await _sleep_until(t0 + (conn.closed if conn.closed is not None else recording_end))
    finally:
        await link.close()
    return outcomes


async def _replay_state(
    conn: RecordedConnection,
    last: bool,
    t0: float,
    connect: Connector,
    host: str,
    port: int,
    order: ByteOrder,
    observed: _Observed,
    end: asyncio.Event,
) -> None:
    """Read the state port like the recorded client: from its opening to its closing
    (the last one: until the replay ends)."""
    await _sleep_until(t0 + conn.opened)
    link = await _open(connect, host, port, Port.STATE, order)

    async def read() -> None:
        while (item := await link.frames.get()) is not None:
            observed.take(decode_reply(item[1], order, Port.STATE))

    reader = asyncio.create_task(read(), name="pymotoros-replay-state")
    try:
        if last or conn.closed is None:
            await end.wait()
        else:
            await _sleep_until(t0 + conn.closed)
    finally:
        reader.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await reader
        await link.close()


def _recorded_final(
    recording: Recording,
) -> tuple[dict[int, tuple[float, ...]], RobotStatus | None]:
    observed = _Observed()
    for message in recording.messages:
        if message.kind is Port.STATE and message.message is not None:
            observed.take(message.message)
    return observed.feedback, observed.status


async def replay(
    recording: Recording,
    host: str,
    ports: Mapping[Port, int],
    *,
    pulse_tolerance: Mapping[int, Sequence[float]] | None = None,
    timing_tolerance: float = DEFAULT_TIMING_TOLERANCE_S,
    connect: Connector | None = None,
) -> ReplayResult:
    """Replay ``recording``'s client side against ``host`` and compare (see the module).

    ``ports`` gives the target's motion, state and IO ports. ``pulse_tolerance`` maps a
    group number to the per-joint tolerance of the final positions (one encoder pulse,
    in rad or m); a group without one is compared within 1e-6.
    Raises :class:`ValueError` for a recording there is nothing to replay in, and
    :class:`ConnectionError` when a port of the target cannot be reached.
    """
    order = recording.order
    if order is None:
        raise ValueError(f"{recording.path}: no Simple Message traffic to replay")
    unknown = [c.index for c in recording.connections if c.kind is None and c.messages]
    if unknown:
        raise ValueError(
            f"{recording.path}: which MotoROS port connection(s) {unknown} went to is not "
            "known (non-standard ports and no telling traffic)"
        )
    open_stream: Connector = connect or asyncio.open_connection
    plans = _plan(recording)
    loop = asyncio.get_running_loop()
    observed = _Observed()
    end = asyncio.Event()
    state_conns = recording.on(Port.STATE)
    t0 = loop.time()
    outcomes: list[_Outcome] = []
    settled: list[bool] = []

    async def run(tg: asyncio.TaskGroup) -> None:
        for conn in state_conns:
            tg.create_task(
                _replay_state(
                    conn,
                    conn is state_conns[-1],
                    t0,
                    open_stream,
                    host,
                    ports[Port.STATE],
                    order,
                    observed,
                    end,
                )
            )
        request_tasks = [
            tg.create_task(
                _replay_requests(
                    steps,
                    conn,
                    t0,
                    open_stream,
                    host,
                    ports[conn.kind or Port.MOTION],
                    order,
                    recording.duration,
                )
            )
            for conn in recording.connections
            if (steps := plans.get(conn.index))
        ]
        try:
            for task in request_tasks:
                outcomes.extend(await task)
            await _sleep_until(t0 + recording.duration)
            _, recorded_status = _recorded_final(recording)
            if state_conns and recorded_status is not None and recorded_status.in_motion == 0:
                observed.watching = True
                try:
                    async with asyncio.timeout(SETTLE_TIMEOUT_S):
                        await observed.still.wait()
                    settled.append(True)
                except TimeoutError:
                    settled.append(False)
        finally:
            end.set()

    try:
        async with asyncio.TaskGroup() as tg:
            await run(tg)
    except ExceptionGroup as group:  # a port that cannot be reached: say that, plainly
        lost = group.subgroup(ConnectionError)
        if lost is None:
            raise
        first: BaseException = lost
        while isinstance(first, BaseExceptionGroup):
            first = first.exceptions[0]
        raise first from None
    replayed_duration = loop.time() - t0
    return _result(
        recording,
        plans,
        outcomes,
        observed,
        pulse_tolerance or {},
        timing_tolerance,
        replayed_duration,
        settled[0] if settled else None,
    )


def _result(
    recording: Recording,
    plans: Mapping[int, Sequence[_Step]],
    outcomes: Sequence[_Outcome],
    observed: _Observed,
    pulse_tolerance: Mapping[int, Sequence[float]],
    timing_tolerance: float,
    replayed_duration: float,
    settled: bool | None,
) -> ReplayResult:
    differences: list[ReplyDiff] = []
    timings: list[RequestTiming] = []
    for outcome in sorted(outcomes, key=lambda o: o.step.number):
        step = outcome.step
        request = step.first.message
        kind = (step.conn.kind or Port.MOTION).value
        request_type = _type_name(step.first.frame.msg_type)
        if step.expects_reply:
            final = step.final_reply
            recorded = _compared(
                reply_summary(
                    final.message if final is not None else None,
                    final.frame if final is not None else None,
                ),
                request,
            )
            replayed = _compared(reply_summary(outcome.reply, outcome.reply_frame), request)
            if recorded != replayed:
                command = getattr(request, "command", None)
                differences.append(
                    ReplyDiff(
                        request=step.number,
                        connection=step.conn.index,
                        port=kind,
                        offset=step.first.offset,
                        request_type=request_type,
                        sequence=getattr(request, "sequence", None),
                        command=None if command is None else MotionCommand.describe(command),
                        recorded=recorded,
                        replayed=replayed,
                    )
                )
        timings.append(
            RequestTiming(
                request=step.number,
                port=kind,
                request_type=request_type,
                recorded_delay=step.recorded_delay,
                replayed_delay=outcome.delay,
                recorded_attempts=len(step.attempts),
                replayed_attempts=outcome.attempts,
            )
        )
    recorded_feedback, _ = _recorded_final(recording)
    positions: list[PositionDiff] = []
    for group in sorted(set(recorded_feedback) | set(observed.feedback)):
        before = recorded_feedback.get(group)
        after = observed.feedback.get(group)
        width = len(before if before is not None else after or ())
        tolerance = tuple(pulse_tolerance.get(group, ()))
        joints = len(tolerance) or width
        tolerance = tolerance + (1e-6,) * (joints - len(tolerance))
        positions.append(
            PositionDiff(
                group=group,
                recorded=None if before is None else before[:joints],
                replayed=None if after is None else after[:joints],
                tolerance=tolerance,
            )
        )
    return ReplayResult(
        requests=sum(len(steps) for steps in plans.values()),
        connections=len(recording.connections),
        recorded_duration=recording.duration,
        replayed_duration=replayed_duration,
        differences=tuple(differences),
        timings=tuple(timings),
        timing_tolerance=timing_tolerance,
        positions=tuple(positions),
        settled=settled,
    )
