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
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Final, TypeAlias

from pymotoros.client.recording import (
    RecordedConnection,
    Recording,
)
from pymotoros.client.replay_plan import (
    ReplayStep,
    replay_plan,
    retried,
)
from pymotoros.client.replay_report import (
    DEFAULT_TIMING_TOLERANCE_S,
    PositionDiff,
    ReplayResult,
    ReplyDiff,
    RequestTiming,
    compared,
    reply_summary,
    type_name,
)
from pymotoros.protocol.constants import (
    ByteOrder,
    CommType,
    MotionCommand,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import Frame, FrameDecoder, decode_reply, encode_frame
from pymotoros.protocol.messages import (
    JointFeedback,
    MotoJointFeedbackEx,
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


REPLY_TIMEOUT_S: Final = 5.0
"""A request the controller does not answer within this is reported as unanswered
(the client's own request timeout, pymotoros.client.connection)."""


CONNECT_TIMEOUT_S: Final = 5.0
"""Connecting to a port of the target: as the client does."""


SETTLE_TIMEOUT_S: Final = 30.0
"""How long after the recorded end the replay waits for the robot to stand still
(ROBOT_STATUS in_motion 0) before it takes the final positions anyway."""


READ_CHUNK: Final = 4096


Connector: TypeAlias = Callable[
    [str, int], Awaitable[tuple[asyncio.StreamReader, asyncio.StreamWriter]]
]


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
    step: ReplayStep
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
    steps: Sequence[ReplayStep],
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
            recorded_final = retried(
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
                again = retried(message)
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
    plans = replay_plan(recording)
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
    plans: Mapping[int, Sequence[ReplayStep]],
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
        request_type = type_name(step.first.frame.msg_type)
        if step.expects_reply:
            final = step.final_reply
            recorded = compared(
                reply_summary(
                    final.message if final is not None else None,
                    final.frame if final is not None else None,
                ),
                request,
            )
            replayed = compared(reply_summary(outcome.reply, outcome.reply_frame), request)
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
