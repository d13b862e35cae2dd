"""The ROS driver's reconnect after a network fault, against the twin (issue 23, item 1).

The driver is :mod:`.ros_driver_like`, a **stand-in** that re-enacts what
``motoman_driver`` + ``simple_message`` do on the wire when a connection fails (see its
docstring for the behaviours and the source files they come from); the real driver needs
ROS, which cannot run here. Every connection goes through a :class:`FaultProxy` on TCP,
the twin is the real servers (the ``pymotoros_twin`` fixture), and the application's side
(planning, calling ``robot_enable``, sending the next goal) is played by the test.

* (a) the motion connection is reset mid-trajectory: the twin stops and clears its queues
  (docs/fidelity.md); the driver reconnects and resends the point it had not got an answer
  for, with its sequence number, and streams the rest of that trajectory; the twin accepts
  it, but the increments it cleared are gone, so the robot ends short of the goal while the
  driver reports the trajectory complete. The application then calls ``robot_enable``
  (START_TRAJ_MODE) and sends a new goal from where the robot is: sequence 0, at the goal.
* (b) the state connection is reset: the driver reconnects after the driver's constant
  delay (scaled down) and receives joint feedback again.
* (c) the driver's end of the motion connection dies while the twin's end stays open and
  silent: the twin refuses (closes at once) every new motion connection while motion is
  queued, then lets the next one replace the old; the driver's retry loop gets through and
  the robot reaches the goal, each point accepted once.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import socket
import struct
import time
from collections.abc import AsyncIterator, Sequence
from contextlib import asynccontextmanager
from dataclasses import dataclass

import pytest

from pymotoros.client import RobotClient
from pymotoros.protocol.constants import MotionCommand, ResultCode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionCtrl, MotoMotionReply
from pymotoros.pytest_plugin import RunningTwin

from .fault_proxy import FaultProxy, Link
from .ros_driver_like import (
    CONNECT_SETTLE_S,
    LOOP_PERIOD_S,
    STATE_RECONNECT_DELAY_S,
    MotionInterface,
    StateInterface,
    TransferState,
    trajectory_points,
)
from .test_network_faults import MOTION_SERVER_OUTPUT, accepted_sequences

GOAL = (0.25, -0.15, 0.2, 0.0, 0.1, 0.0)
STATE_DELAY_SCALE = 25
"""The state side's 5 s reconnect delay, divided by this in the tests (0.2 s)."""
GATE_TIMEOUT_S = 10.0
MOVE_TIMEOUT_S = 20.0
AT_POINT = 30
"""The fault strikes once the driver has this many points accepted (of 63): mid-stream,
with about half a second of motion queued in the twin."""


class GatedProxy(FaultProxy):
    """A :class:`FaultProxy` that can hold new connections at the door.

    While :attr:`gate` is clear a connection is accepted (the client is connected) but not
    yet forwarded to the twin, so a test can look at the twin between a fault and the
    driver's reconnect, however fast that is. Bounded: a held connection waits at most
    :data:`GATE_TIMEOUT_S`.
    """

    def __init__(self, upstream_host: str, upstream_port: int) -> None:
        super().__init__(upstream_host, upstream_port)
        self.gate = asyncio.Event()
        self.gate.set()
        self.held = 0

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if not self.gate.is_set():
            self.held += 1
            self._notify()
            async with asyncio.timeout(GATE_TIMEOUT_S):
                await self.gate.wait()
        await super()._accept(reader, writer)


@dataclass
class Cell:
    """The twin, the proxies in front of it, the stand-in driver and the operator's view."""

    twin: RunningTwin
    motion_proxy: GatedProxy
    state_proxy: FaultProxy
    motion: MotionInterface
    state: StateInterface
    watcher: RobotClient
    """A state client straight to the twin (no proxy): the operator's view, and the planner."""

    def plan(self, goal: Sequence[float], speed_scale: float) -> list[JointTrajPtFull]:
        """What MoveIt would send: a timed trajectory from the driver's joint state to ``goal``."""
        start = self.state.joint_state()
        assert start is not None, "the driver has no joint state yet"
        return trajectory_points(self.watcher.plan(start, goal, speed_scale=speed_scale))

    async def at_rest(self) -> tuple[float, ...]:
        await self.watcher.tracker.wait_for(
            lambda s: s.status is not None and s.status.in_motion is False,
            timeout_s=MOVE_TIMEOUT_S,
            what="the robot to stop",
        )
        positions = self.watcher.state.positions(0)
        assert positions is not None
        return tuple(positions)

    async def state_caught_up(self, positions: Sequence[float]) -> None:
        """Wait until the driver's joint state shows ``positions`` (it lags the twin a cycle)."""

        def there() -> bool:
            mine = self.state.joint_state()
            return mine is not None and distance(mine, positions) < 1e-5

        await self.state.recorder.wait_until(there, timeout_s=5.0)


async def still(cell: Cell, *, checks: int = 50) -> tuple[float, ...]:
    """The operator's view of group 0 once two samples 0.1 s apart agree (bounded)."""
    previous: tuple[float, ...] | None = None
    for _ in range(checks):
        await asyncio.sleep(0.1)
        positions = cell.watcher.state.positions(0)
        assert positions is not None
        if previous is not None and distance(positions, previous) < 1e-6:
            return tuple(positions)
        previous = tuple(positions)
    pytest.fail(f"the robot did not come to rest within {checks * 0.1:g} s")


@asynccontextmanager
async def cell_with_driver(twin: RunningTwin) -> AsyncIterator[Cell]:
    """Start the proxies, the operator's view and the stand-in driver (state node first,
    as a launch file does), and wait until the driver is connected and has a joint state."""
    async with contextlib.AsyncExitStack() as stack:
        motion_proxy = GatedProxy(twin.host, twin.motion)
        await motion_proxy.start()
        stack.push_async_callback(motion_proxy.close)
        state_proxy = await FaultProxy(twin.host, twin.state).start()
        stack.push_async_callback(state_proxy.close)
        watcher = RobotClient("127.0.0.1", state_port=twin.state, robot="hc10")
        await watcher.connect(motion=False, io=False)
        stack.push_async_callback(watcher.close)
        state = await stack.enter_async_context(
            StateInterface(
                "127.0.0.1",
                state_proxy.port,
                reconnect_delay_s=STATE_RECONNECT_DELAY_S / STATE_DELAY_SCALE,
            )
        )
        motion = await stack.enter_async_context(
            MotionInterface("127.0.0.1", motion_proxy.port, joint_state=state.joint_state)
        )
        await motion.recorder.wait_until(lambda: motion.conn.connected)
        await state.recorder.wait_until(lambda: state.joint_state() is not None)
        yield Cell(twin, motion_proxy, state_proxy, motion, state, watcher)


def distance(a: Sequence[float], b: Sequence[float]) -> float:
    """Largest joint difference (rad)."""
    return max(abs(x - y) for x, y in zip(a, b, strict=True))


def motion_commands(motion: MotionInterface, connection: int) -> list[int]:
    """The MOTO_MOTION_CTRL commands the driver sent on ``connection``, in order."""
    return [
        e.request.command
        for e in motion.exchanges
        if e.connection == connection and isinstance(e.request, MotoMotionCtrl)
    ]


def accepted_across(motion: MotionInterface) -> list[int]:
    """Sequences the driver got SUCCESS for, over every connection, in order."""
    return [
        seq
        for c in range(motion.conn.connections)
        for seq, result in motion.points_on(c)
        if result == ResultCode.SUCCESS
    ]


async def enable_and_stream(cell: Cell, speed_scale: float) -> list[JointTrajPtFull]:
    """robot_enable, then a goal; returns the points the driver is streaming."""
    assert await cell.motion.enable(), cell.motion.recorder.notes
    points = cell.plan(GOAL, speed_scale)
    assert await cell.motion.execute(points), cell.motion.recorder.notes
    return points


def sever_driver_side(link: Link) -> None:
    """The driver's end of ``link`` gets RST; the twin's end stays open and silent.

    What a NAT or firewall that forgets a connection does, or a driver PC that reboots:
    the twin's socket never sees FIN or RST, so (no keepalive) its slot stays taken.
    """
    sock = link.client_writer.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    link.client_writer.transport.abort()
    for task in link.tasks:
        task.cancel()


async def reset_with_motion_queued(cell: Cell, points: Sequence[JointTrajPtFull]) -> int:
    """Once the driver streams past AT_POINT, with the twin's points well ahead of the
    robot (motion queued), reset the motion connection; the driver notices, reconnects
    at once (its connect succeeds at the proxy) and sends the point it had no answer
    for, which waits at the door with it. The number of that point."""
    motion = cell.motion
    await motion.recorder.wait_until(lambda: motion.current_point >= AT_POINT)
    robot = cell.watcher.state.positions(0)
    assert robot is not None
    ahead = distance(points[motion.current_point - 1].pos[:6], robot)
    assert ahead > 0.02, f"only {ahead:.4f} rad queued: the machine is too slow for this test"
    cell.motion_proxy.gate.clear()  # the reconnect will wait at the door
    cell.motion_proxy.reset()
    await cell.motion_proxy.wait_until(lambda: cell.motion_proxy.held == 1)
    return motion.current_point


async def test_reset_mid_trajectory_driver_resumes_and_reaches_the_goal(
    pymotoros_twin: RunningTwin,
) -> None:
    """Exact (the default): the twin keeps the queued increments when the motion
    connection is reset, as MotoROS 1.9.12 does (§2.2); the driver's new connection
    resumes them and streams the rest, and the robot reaches the goal."""
    async with cell_with_driver(pymotoros_twin) as cell:
        motion = cell.motion
        points = await enable_and_stream(cell, speed_scale=0.1)
        failed_at = await reset_with_motion_queued(cell, points)
        # the twin meanwhile: motion connection gone, the robot still, the queue kept
        # (so ROBOT_STATUS keeps in_motion 1, as MotoROS computes it from the queues)
        stopped_at = await still(cell)
        assert pymotoros_twin.call(lambda c: c.read_io_bit(MOTION_SERVER_OUTPUT).value) == 0
        assert pymotoros_twin.call(lambda c: c.has_queued_motion())
        status = cell.watcher.state.status
        assert status is not None
        assert status.in_motion is True
        assert distance(stopped_at, GOAL) > 1e-2
        cell.motion_proxy.gate.set()
        await motion.recorder.wait_until(
            lambda: motion.state is TransferState.IDLE, timeout_s=MOVE_TIMEOUT_S
        )
        assert motion.conn.connections == 2
        assert motion.points_on(1)[0] == (failed_at, ResultCode.SUCCESS)
        assert accepted_across(motion) == list(range(len(points)))
        assert motion.aborted is None
        # the kept increments ran on the new connection, then the rest: at the goal
        assert distance(await cell.at_rest(), GOAL) < 1e-3
    # it works because the driver relies on the resume: the lint says so
    assert_reconnect_found(pymotoros_twin, safe=False)


def assert_reconnect_found(twin: RunningTwin, *, safe: bool) -> None:
    """The driver's reconnect carried on streaming (its first request a point, not
    STOP_MOTION): the client lint reports it in either fidelity setting, in safe with
    what a robot would have done (docs/sim.md, reconnect-resumed-motion)."""
    found = [f for f in twin.lint_findings() if f.code == "reconnect-resumed-motion"]
    assert len(found) == 1, twin.lint_findings()
    assert "its first request was JOINT_TRAJ_PT_FULL, not STOP_MOTION" in found[0].text
    cleared = "safe cleared them, but a robot would have kept them and resumed them"
    assert (cleared in found[0].text) is safe, found[0].text


@pytest.mark.pymotoros(fidelity="safe")
async def test_reset_mid_trajectory_driver_resumes_and_application_recovers(
    pymotoros_twin: RunningTwin,
) -> None:
    """Safe: the twin clears the queues at the reset, so the driver's resumed stream
    ends short of the goal; the application recovers with a new goal."""
    async with cell_with_driver(pymotoros_twin) as cell:
        motion = cell.motion
        points = await enable_and_stream(cell, speed_scale=0.1)
        assert motion_commands(motion, 0)[:2] == [
            MotionCommand.START_TRAJ_MODE,  # robot_enable
            MotionCommand.CHECK_MOTION_READY,  # send_to_robot, before the first point
        ]
        failed_at = await reset_with_motion_queued(cell, points)
        assert motion.state is TransferState.STREAMING
        # the twin meanwhile: motion connection gone, queues cleared, robot at rest
        stopped_at = await cell.at_rest()
        assert pymotoros_twin.call(lambda c: c.read_io_bit(MOTION_SERVER_OUTPUT).value) == 0
        assert not pymotoros_twin.call(lambda c: c.has_queued_motion())
        assert distance(stopped_at, GOAL) > 1e-2
        cell.motion_proxy.gate.set()
        await motion.recorder.wait_until(
            lambda: motion.state is TransferState.IDLE, timeout_s=MOVE_TIMEOUT_S
        )
        # the driver: no re-arm and no CHECK_MOTION_READY on the new connection; the same
        # point again, with its own sequence number, then the rest; every point accepted
        # once (the driver's view), none skipped; it believes the trajectory complete
        assert motion.conn.connections == 2
        assert motion_commands(motion, 1) == []
        assert motion.points_on(1)[0] == (failed_at, ResultCode.SUCCESS)
        assert accepted_across(motion) == list(range(len(points)))
        assert motion.aborted is None
        # the twin received on the new connection exactly the rest of the trajectory
        twin_side = accepted_sequences(cell.motion_proxy.links[1])
        assert twin_side == list(range(failed_at, len(points)))
        assert pymotoros_twin.call(lambda c: c.read_io_bit(MOTION_SERVER_OUTPUT).value) == 1
        # but the increments the twin cleared at the reset are lost: the robot ends short
        # (MotoROS 1.9.12 keeps them and would resume them on the new connection, §2.2)
        ended_at = await cell.at_rest()
        assert distance(ended_at, GOAL) > 1e-2
        # the application re-arms (robot_enable) and sends a new goal from where it is
        await cell.state_caught_up(ended_at)
        before = len(motion.exchanges)
        second = await enable_and_stream(cell, speed_scale=0.3)
        assert distance(second[0].pos[:6], ended_at) < 1e-4
        await motion.recorder.wait_until(
            lambda: motion.state is TransferState.IDLE, timeout_s=MOVE_TIMEOUT_S
        )
        assert motion.aborted is None
        replies = [
            (e.request.command, e.reply.result)
            for e in motion.exchanges[before:]
            if isinstance(e.request, MotoMotionCtrl) and isinstance(e.reply, MotoMotionReply)
        ]
        assert replies == [
            (MotionCommand.START_TRAJ_MODE, ResultCode.SUCCESS),
            (MotionCommand.CHECK_MOTION_READY, ResultCode.TRUE),
        ]
        sent = [
            e.request.sequence
            for e in motion.exchanges[before:]
            if isinstance(e.request, JointTrajPtFull)
        ]
        assert sent[0] == 0
        restart = accepted_sequences(cell.motion_proxy.links[1])[len(twin_side) :]
        assert restart == list(range(len(second)))
        assert distance(await cell.at_rest(), GOAL) < 1e-3
    # on a robot the reconnect would have resumed the cleared increments: the lint says so
    assert_reconnect_found(pymotoros_twin, safe=True)


async def test_state_reset_driver_reconnects_after_its_delay(
    pymotoros_twin: RunningTwin,
) -> None:
    async with cell_with_driver(pymotoros_twin) as cell:
        state = cell.state
        await state.recorder.wait_until(lambda: state.feedback_per_connection.get(0, 0) >= 5)
        delay = state.reconnect_delay_s
        cell.state_proxy.reset()
        await state.recorder.wait_until(lambda: state.feedback_per_connection.get(1, 0) >= 5)
        lost = state.lost_at[0]
        reconnected = [at for at, ok in state.conn.attempts if ok][1]
        # one failed receive, then the driver's sleep, then one connect that succeeds
        assert len(state.lost_at) == 1
        assert delay <= reconnected - lost < delay + 2.0
        assert state.conn.connections == 2
        assert [ok for _, ok in state.conn.attempts] == [True, True]
        # the feedback is the twin's: the driver's joint state matches the operator's view
        here = await cell.at_rest()
        await cell.state_caught_up(here)
        assert state.status is not None
        # the motion connection never noticed: still the first one, still usable
        assert cell.motion.conn.connections == 1
        assert await cell.motion.controller_ready() is False  # not enabled yet: FALSE
        assert motion_commands(cell.motion, 0) == [MotionCommand.CHECK_MOTION_READY]


async def test_reconnect_while_old_motion_connection_is_half_open(
    pymotoros_twin: RunningTwin,
) -> None:
    async with cell_with_driver(pymotoros_twin) as cell:
        motion, proxy = cell.motion, cell.motion_proxy
        points = await enable_and_stream(cell, speed_scale=0.1)
        await motion.recorder.wait_until(lambda: motion.current_point >= AT_POINT)
        assert pymotoros_twin.call(lambda c: c.has_queued_motion())
        severed_at = time.monotonic()
        sever_driver_side(proxy.links[0])
        await motion.recorder.wait_until(
            lambda: motion.state is TransferState.IDLE, timeout_s=MOVE_TIMEOUT_S
        )
        assert motion.aborted is None, motion.recorder.notes
        # the driver's end failed on the point in flight (no reply) ...
        failed_at, no_reply = motion.points_on(0)[-1]
        assert no_reply is None
        # ... and every reconnect but the last was refused while the twin's old
        # connection held queued motion: the connect worked, the point got no reply
        last = motion.conn.connections - 1
        assert last >= 2, motion.recorder.notes
        for c in range(1, last):
            assert motion.points_on(c) == [(failed_at, None)], motion.recorder.notes
        # ... then let the next connection replace the old one (whose queue had run out):
        # the same point again, then the rest; each point accepted exactly once
        assert motion.points_on(last)[0] == (failed_at, ResultCode.SUCCESS)
        assert accepted_across(motion) == list(range(len(points)))
        assert motion_commands(motion, last) == []
        # the retries follow the driver's loop: one connect per turn + 250 ms, no faster
        connects = [at for at, ok in motion.conn.attempts if ok and at > severed_at]
        gaps = [b - a for a, b in itertools.pairwise(connects)]
        assert all(gap >= CONNECT_SETTLE_S + LOOP_PERIOD_S for gap in gaps), gaps
        # nothing the twin accepted was lost (the queue ran out, it was not cleared)
        twin_old = accepted_sequences(proxy.links[0])
        twin_new = accepted_sequences(proxy.links[-1])
        assert twin_new[0] in (twin_old[-1], twin_old[-1] + 1)
        assert twin_new[-1] == len(points) - 1
        assert distance(await cell.at_rest(), GOAL) < 1e-3
        assert pymotoros_twin.call(lambda c: c.read_io_bit(MOTION_SERVER_OUTPUT).value) == 1
