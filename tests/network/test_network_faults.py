"""What the client and the twin do when the network between them fails (issue 23).

Every test runs the real servers on TCP (the ``pymotoros_twin`` fixture) with a
:class:`FaultProxy` in front of each MotoROS port, and checks the specified outcome:

* latency with jitter, and bytes delivered one at a time: moves complete at the goal;
* a stalled state stream: the client stops streaming, sends STOP_MOTION while the motion
  port answers, and raises :class:`StateStreamLostError` within its bound;
* a peer that vanishes without FIN: the same error, saying STOP_MOTION could not be sent;
* a connection reset mid-trajectory: the twin clears its queues and stops (docs/fidelity.md),
  the client reconnects and finishes the move from where the robot stopped.

In every case the bytes the twin received prove that no point was accepted twice and
none was skipped: the accepted sequence numbers are 0, 1, 2, … on each connection.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Sequence
from contextlib import asynccontextmanager
from dataclasses import dataclass

import pytest

from pymotoros.client import (
    ClientError,
    ConnectionLostError,
    MoveResult,
    RobotClient,
    StateStreamLostError,
)
from pymotoros.client.streaming import BusyPolicy
from pymotoros.client.watchdog import DEFAULT_STATE_STALL_S
from pymotoros.protocol.constants import (
    ByteOrder,
    InvalidSubcode,
    MotionCommand,
    Port,
    ResultCode,
)
from pymotoros.protocol.framing import FrameDecoder
from pymotoros.protocol.messages import (
    JointTrajPtFull,
    MotoMotionCtrl,
    MotoMotionReply,
    WireMessage,
)
from pymotoros.pytest_plugin import RunningTwin

from .fault_proxy import FaultProxy, Link

GOAL = (0.25, -0.15, 0.2, 0.0, 0.1, 0.0)
HOME = (0.0,) * 6
MOTION_SERVER_OUTPUT = 11124  # OT#893: ON while a motion connection exists (§6)


@dataclass
class Proxies:
    motion: FaultProxy
    state: FaultProxy
    io: FaultProxy

    def all(self) -> tuple[FaultProxy, FaultProxy, FaultProxy]:
        return (self.motion, self.state, self.io)


@asynccontextmanager
async def proxied(twin: RunningTwin, **faults: float | bool) -> AsyncIterator[Proxies]:
    proxies = Proxies(
        await FaultProxy(twin.host, twin.motion, seed=1, **faults).start(),  # type: ignore[arg-type]
        await FaultProxy(twin.host, twin.state, seed=2, **faults).start(),  # type: ignore[arg-type]
        await FaultProxy(twin.host, twin.io, seed=3, **faults).start(),  # type: ignore[arg-type]
    )
    try:
        yield proxies
    finally:
        for proxy in proxies.all():
            await proxy.close()


def client_through(proxies: Proxies, **options: float) -> RobotClient:
    return RobotClient(
        "127.0.0.1",
        motion_port=proxies.motion.port,
        state_port=proxies.state.port,
        io_port=proxies.io.port,
        robot="hc10",
        **options,  # type: ignore[arg-type]
    )


def exchange(link: Link) -> list[tuple[WireMessage, WireMessage | None]]:
    """The motion port's requests as the twin received them, each with its reply."""
    requests = FrameDecoder(ByteOrder.LITTLE)
    requests.feed(link.upstream_bytes)
    replies = FrameDecoder(ByteOrder.LITTLE)
    replies.feed(link.downstream_bytes)
    out: list[tuple[WireMessage, WireMessage | None]] = []
    while (request := requests.next_request(Port.MOTION)) is not None:
        out.append((request, replies.next_reply(Port.MOTION)))
    return out


def accepted_sequences(link: Link) -> list[int]:
    """Sequence numbers of the points the twin answered SUCCESS, in arrival order."""
    return [
        req.sequence
        for req, rep in exchange(link)
        if isinstance(req, JointTrajPtFull)
        and isinstance(rep, MotoMotionReply)
        and rep.result == ResultCode.SUCCESS
    ]


def assert_no_point_twice_or_skipped(link: Link) -> list[int]:
    """Accepted: 0..k-1 exactly once each; a refused (BUSY) point is resent, never skipped."""
    sent = [req.sequence for req, _ in exchange(link) if isinstance(req, JointTrajPtFull)]
    accepted = accepted_sequences(link)
    assert accepted == list(range(len(accepted)))
    # each point is sent again only while it was not accepted (BUSY): sent is non-decreasing
    assert sent == sorted(sent)
    assert set(sent) <= set(range(len(accepted) + 1))
    return accepted


def distance(a: Sequence[float], b: Sequence[float]) -> float:
    """Largest joint difference (rad)."""
    return max(abs(x - y) for x, y in zip(a, b, strict=True))


async def streamed_move(client: RobotClient) -> MoveResult:
    """A slow move sampled every 4 ms: far more points than MotoROS queues (0.8 s, §5.1),
    so the client is still streaming (through BUSY) when a fault strikes."""
    start = await client.current_positions(0)
    trajectory = client.plan(start, GOAL, speed_scale=0.05, sample_period=0.004)
    assert len(trajectory.points) > 300
    return await client.execute(trajectory)


@asynccontextmanager
async def watch_directly(twin: RunningTwin) -> AsyncIterator[RobotClient]:
    """A state-only client straight to the twin (not through the proxy): the operator's view."""
    watcher = RobotClient("127.0.0.1", state_port=twin.state, robot="hc10")
    await watcher.connect(motion=False, io=False)
    try:
        yield watcher
    finally:
        await watcher.close()


async def wait_until_still(watcher: RobotClient) -> None:
    await watcher.tracker.wait_for(
        lambda s: s.status is not None and s.status.in_motion is False,
        timeout_s=10.0,
        what="the robot to stop",
    )


async def test_latency_and_jitter_moves_still_complete(pymotoros_twin: RunningTwin) -> None:
    async with proxied(pymotoros_twin, latency_s=0.004, jitter_s=0.012) as proxies:
        async with client_through(proxies, timeout_s=5.0) as client:
            await client.start_trajectory_mode()
            result = await client.move_joints(GOAL)
            assert distance(result.final_positions, GOAL) < 1e-3
            back = await client.move_joints(HOME)
            assert distance(back.final_positions, HOME) < 1e-3
        link = proxies.motion.links[0]
        accepted = accepted_sequences(link)
        # two moves on one connection: each trajectory's sequences start again at 0
        restart = accepted.index(0, 1)
        assert accepted[:restart] == list(range(restart))
        assert accepted[restart:] == list(range(len(accepted) - restart))
        assert restart == result.stream.points


async def test_busy_retries_send_no_point_twice_and_skip_none(
    pymotoros_twin: RunningTwin,
) -> None:
    """Points 4 ms apart, each offered the moment the one before is accepted
    (``BusyPolicy.IMMEDIATE``: the default paced offers wait for the slot to free and
    rarely meet BUSY): every point goes through BUSY retries. (No added latency here: a
    round trip longer than 4 ms frees the slot before the next offer.)"""
    async with (
        proxied(pymotoros_twin) as proxies,
        client_through(proxies) as client,
    ):
        client.streamer.busy_policy = BusyPolicy.IMMEDIATE
        await client.start_trajectory_mode()
        start = await client.current_positions(0)
        trajectory = client.plan(start, GOAL, speed_scale=0.1, sample_period=0.004)
        result = await client.execute(trajectory)
        assert distance(result.final_positions, GOAL) < 1e-3
    link = proxies.motion.links[0]
    busy = [
        rep
        for req, rep in exchange(link)
        if isinstance(req, JointTrajPtFull)
        and isinstance(rep, MotoMotionReply)
        and rep.result == ResultCode.BUSY
    ]
    assert busy, "the queue never filled: no BUSY to retry"
    assert result.stream.busy_replies == len(busy)
    accepted = assert_no_point_twice_or_skipped(link)
    assert len(accepted) == len(trajectory.points)


@pytest.mark.pymotoros(fidelity="safe")
async def test_bytes_one_at_a_time_moves_still_complete(pymotoros_twin: RunningTwin) -> None:
    """Safe: requests delivered a byte at a time are reassembled."""
    async with proxied(pymotoros_twin, one_byte=True) as proxies:
        async with client_through(proxies) as client:
            await client.start_trajectory_mode()
            result = await client.move_joints(GOAL, speed_scale=0.5)
            assert distance(result.final_positions, GOAL) < 1e-3
        accepted = assert_no_point_twice_or_skipped(proxies.motion.links[0])
        assert len(accepted) == result.stream.points == len(result.trajectory.points)


async def test_bytes_one_at_a_time_are_refused_as_motoros_does(
    pymotoros_twin: RunningTwin,
) -> None:
    """Exact (the default): each read holds one byte, fewer than a header, and MotoROS
    answers it INVALID/3001 without keeping it; a client cannot get one request through,
    and says so rather than moving."""
    async with proxied(pymotoros_twin, one_byte=True) as proxies:
        with pytest.raises(ClientError) as caught:
            async with client_through(proxies, timeout_s=2.0) as client:
                await client.start_trajectory_mode()
        decoder = FrameDecoder(ByteOrder.LITTLE)
        decoder.feed(proxies.motion.links[0].downstream_bytes)
        replies = []
        while (reply := decoder.next_reply(Port.MOTION)) is not None:
            replies.append(reply)
        assert len(replies) > 1, "the twin did not answer each piece"
        # the first piece: 3001 (sequence and command echoed as far as they came); the
        # later pieces are parsed as new messages: 3001 or 3003, never a success
        first = replies[0]
        assert isinstance(first, MotoMotionReply)
        assert first.subcode == InvalidSubcode.MSGSIZE
        invalid = {InvalidSubcode.MSGSIZE, InvalidSubcode.MSGTYPE}
        assert all(isinstance(r, MotoMotionReply) and r.subcode in invalid for r in replies)
        # the pieces' answers do not echo the request, so the client waits in vain for its
        # reply: a timeout naming the request (what a robot gives too)
        assert "MotoMotionCtrl" in str(caught.value), caught.value
        assert not pymotoros_twin.call(lambda c: c.has_queued_motion())


async def test_stalled_state_stream_stops_the_move_within_its_bound(
    pymotoros_twin: RunningTwin,
) -> None:
    async with (
        proxied(pymotoros_twin) as proxies,
        watch_directly(pymotoros_twin) as watcher,
        client_through(proxies) as client,
    ):
        assert client.streamer.state_stall_s == DEFAULT_STATE_STALL_S <= 1.0
        await client.start_trajectory_mode()
        motion = proxies.motion
        move = asyncio.create_task(streamed_move(client))
        await motion.wait_until(
            lambda: move.done() or len(accepted_sequences(motion.links[0])) >= 30
        )
        proxies.state.stall_downstream()
        stalled_at = time.monotonic()
        with pytest.raises(StateStreamLostError) as caught:
            await move
        noticed = time.monotonic() - stalled_at
        error = caught.value
        # noticed at the bound (the silence measured then), then the STOP_MOTION round
        # trip; the margins are for a loaded CI machine
        assert noticed < DEFAULT_STATE_STALL_S + 1.0
        assert error.silent_s is not None
        assert DEFAULT_STATE_STALL_S <= error.silent_s < DEFAULT_STATE_STALL_S + 0.5
        assert error.stopped
        link = motion.links[0]
        assert error.accepted_points == len(assert_no_point_twice_or_skipped(link))
        assert error.accepted_points < error.total_points  # streaming stopped early
        assert len(error.positions) == 6
        text = str(error)
        assert "stalled" in text
        assert "STOP_MOTION acknowledged" in text
        assert f"{error.accepted_points} of {error.total_points} points" in text
        # STOP_MOTION reached the twin after the last point, and no point after it
        requests = [req for req, _ in exchange(link)]
        stops = [
            i
            for i, req in enumerate(requests)
            if isinstance(req, MotoMotionCtrl) and req.command == MotionCommand.STOP_MOTION
        ]
        assert stops, "the twin never received STOP_MOTION"
        # (the first is the one every motion connection starts with, docs/client.md)
        assert not any(isinstance(r, JointTrajPtFull) for r in requests[stops[-1] :])
        # the robot stopped short of the goal (the operator's direct view says so)
        await wait_until_still(watcher)
        pos = watcher.state.positions(0)
        assert pos is not None
        assert distance(pos, GOAL) > 1e-2
        assert not pymotoros_twin.call(lambda c: c.has_queued_motion())


async def test_a_vanished_peer_is_noticed_and_reported(pymotoros_twin: RunningTwin) -> None:
    async with proxied(pymotoros_twin) as proxies:
        client = client_through(proxies)
        await client.connect()
        try:
            await client.start_trajectory_mode()
            motion = proxies.motion
            move = asyncio.create_task(streamed_move(client))
            await motion.wait_until(
                lambda: move.done() or len(accepted_sequences(motion.links[0])) >= 10
            )
            for proxy in proxies.all():
                proxy.vanish()  # no FIN, no RST: the sockets just go quiet
            with pytest.raises(StateStreamLostError) as caught:
                async with asyncio.timeout(DEFAULT_STATE_STALL_S + 3.0):
                    await move  # stall bound + 1 s for the unanswered point + 1 s for STOP
            error = caught.value
            assert not error.stopped
            assert "STOP_MOTION could not be sent" in str(error)
            assert "stop the robot on the pendant" in str(error)
            assert_no_point_twice_or_skipped(motion.links[0])
        finally:
            await client.close()


async def wait_until_unmoving(watcher: RobotClient, *, checks: int = 100) -> None:
    """The feedback unchanged over two state cycles (bounded): the robot stands even where
    ROBOT_STATUS keeps ``in_motion`` 1 because increments are queued (fidelity exact)."""
    previous = None
    for _ in range(checks):
        await asyncio.sleep(0.05)
        positions = watcher.state.positions(0)
        if previous is not None and positions is not None and distance(positions, previous) < 1e-7:
            return
        previous = positions
    pytest.fail(f"the robot still moved after {checks * 0.05:g} s")


@pytest.mark.parametrize(
    "fidelity",
    [
        pytest.param("exact", marks=pytest.mark.pymotoros(fidelity="exact")),
        pytest.param("safe", marks=pytest.mark.pymotoros(fidelity="safe")),
    ],
)
async def test_reset_mid_trajectory_twin_stops_and_client_resumes(
    pymotoros_twin: RunningTwin, fidelity: str
) -> None:
    """The twin stops at the reset; exact keeps the queued increments (MotoROS 1.9.12),
    safe clears them. Either way our client, connecting again, finds the robot where it
    stopped (in exact its connect-time STOP_MOTION clears the kept queue) and moves on."""
    async with proxied(pymotoros_twin) as proxies, watch_directly(pymotoros_twin) as watcher:
        client = client_through(proxies)
        await client.connect()
        await client.start_trajectory_mode()
        motion = proxies.motion
        move = asyncio.create_task(streamed_move(client))
        await motion.wait_until(
            lambda: move.done() or len(accepted_sequences(motion.links[0])) >= 30
        )
        motion.reset()
        with pytest.raises(ConnectionLostError) as caught:
            await move
        assert not isinstance(caught.value, StateStreamLostError)  # the state port is up
        await client.close()
        first = assert_no_point_twice_or_skipped(motion.links[0])
        assert len(first) >= 30
        # the twin: motion connection gone, robot stopped short of the goal, the queue
        # kept (exact) or cleared (safe)
        await wait_until_unmoving(watcher)
        # (this client streams a point per 4 ms tick, so at most a few entries are queued
        # at the reset: exact keeps them, safe clears them)
        if fidelity == "safe":
            assert not pymotoros_twin.call(lambda c: c.has_queued_motion())
        assert pymotoros_twin.call(lambda c: c.read_io_bit(MOTION_SERVER_OUTPUT).value) == 0
        stopped_at = watcher.state.positions(0)
        assert stopped_at is not None
        assert distance(stopped_at, GOAL) > 1e-2
        # and it stays there: our client stops what was kept the moment it connects
        async with client_through(proxies) as again:
            assert not pymotoros_twin.call(lambda c: c.has_queued_motion())
            await again.start_trajectory_mode()
            here = await again.current_positions((0,))
            assert distance(here, stopped_at) < 1e-3
            result = await again.move_joints(GOAL)
        assert distance(result.final_positions, GOAL) < 1e-3
        second = assert_no_point_twice_or_skipped(motion.links[1])
        assert len(second) == len(result.trajectory.points)
