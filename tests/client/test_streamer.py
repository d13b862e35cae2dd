"""TrajectoryStreamer on its own: a fake motion port, a fake state source, a fake clock."""

from __future__ import annotations

import ast
from collections.abc import Callable
from pathlib import Path

import pytest

from pymotoros.client import BusyTimeoutError, ConnectionLostError, TrajectoryStreamer
from pymotoros.client.motion_port import MotionReadiness
from pymotoros.client.pacing import BUSY_BACKOFF_FIRST_S, BUSY_BACKOFF_MAX_S, BusyPolicy
from pymotoros.client.planning import JointTrajectory, TrajectoryPoint
from pymotoros.client.state import RobotState
from pymotoros.models import controller_model, robot_model
from pymotoros.protocol.constants import MsgType, ResultCode
from pymotoros.protocol.messages import MotoMotionReply, WireMessage

CLIENT = Path(__file__).resolve().parents[2] / "src" / "pymotoros" / "client"
BACKOFF = [BUSY_BACKOFF_FIRST_S, 2 * BUSY_BACKOFF_FIRST_S, BUSY_BACKOFF_MAX_S, BUSY_BACKOFF_MAX_S]
"""The sleeps between four BUSY replies to one point."""


class FakeClock:
    """Time moves only when someone sleeps; every sleep is recorded."""

    def __init__(self) -> None:
        self.t = 0.0
        self.sleeps: list[float] = []

    def now(self) -> float:
        return self.t

    async def sleep(self, seconds: float) -> None:
        self.sleeps.append(seconds)
        self.t += seconds


class FakePort:
    """Answers every point with ``busy`` BUSY replies, then SUCCESS (or BUSY for ever)."""

    def __init__(self, busy: int) -> None:
        self.busy = busy
        self.sent: list[WireMessage] = []
        self._left = busy

    async def request_motion(
        self, message: WireMessage, *, timeout_s: float | None = None
    ) -> MotoMotionReply:
        self.sent.append(message)
        sequence = getattr(message, "sequence", 0)
        if self._left != 0 and sequence > 0:
            self._left -= 1
            return MotoMotionReply(0, sequence, int(MsgType.JOINT_TRAJ_PT_FULL), ResultCode.BUSY, 0)
        self._left = self.busy
        return MotoMotionReply(0, sequence, int(MsgType.JOINT_TRAJ_PT_FULL), ResultCode.SUCCESS, 0)

    async def queue_count(self, group: int = 0) -> int:
        return 0

    async def check_motion_ready(self) -> MotionReadiness:
        return MotionReadiness(True, 0, None, "ready", "")


class FakeStates:
    def __init__(self, error: ConnectionLostError | None = None) -> None:
        self.state = RobotState()
        self.error = error

    async def next_state(self) -> RobotState:
        return self.state

    def add_listener(self, listener: Callable[[RobotState], None]) -> Callable[[], None]:
        return lambda: None


def _trajectory(points: int) -> JointTrajectory:
    zero = (0.0,) * 6
    return JointTrajectory(
        tuple(TrajectoryPoint(0.1 * i, zero, zero) for i in range(points)), 0.1 * (points - 1)
    )


def _streamer(
    port: FakePort,
    clock: FakeClock,
    states: FakeStates | None = None,
    policy: BusyPolicy = BusyPolicy.PACED,
) -> TrajectoryStreamer:
    return TrajectoryStreamer(
        port,
        states or FakeStates(),
        robot_model("hc10"),
        controller_model("yrc1000"),
        clock=clock,
        busy_policy=policy,
    )


async def test_busy_back_off_sleeps_on_the_injected_clock() -> None:
    clock = FakeClock()
    port = FakePort(busy=4)
    stats = await _streamer(port, clock, policy=BusyPolicy.IMMEDIATE).send_points(
        _trajectory(3), (0,)
    )
    assert stats.points == 3
    assert stats.busy_replies == 8
    assert stats.offers == 11
    assert clock.sleeps == pytest.approx(BACKOFF * 2)
    assert stats.elapsed_s == pytest.approx(sum(clock.sleeps))


async def test_paced_offers_wait_one_period_after_the_point_that_holds_the_slot() -> None:
    """Point 1 follows point 0 at once (sequence 0 takes no pending slot, §3.4); point 2
    is first offered one interpolation period (4 ms on a YRC1000) after point 1 was sent."""
    clock = FakeClock()
    port = FakePort(busy=4)
    stats = await _streamer(port, clock).send_points(_trajectory(3), (0,))
    assert stats.points == 3
    assert stats.busy_replies == 8
    assert clock.sleeps == pytest.approx([*BACKOFF, 0.004, *BACKOFF])


async def test_busy_budget_is_measured_on_the_injected_clock() -> None:
    clock = FakeClock()
    port = FakePort(busy=-1)  # BUSY for ever
    with pytest.raises(BusyTimeoutError) as info:
        await _streamer(port, clock).send_points(_trajectory(3), (0,), busy_timeout_s=0.05)
    assert info.value.point == 1
    assert 0.05 < clock.now() < 0.06


async def test_a_lost_state_stream_stops_streaming() -> None:
    states = FakeStates(ConnectionLostError("state connection lost"))
    with pytest.raises(ConnectionLostError):
        await _streamer(FakePort(busy=0), FakeClock(), states).send_points(_trajectory(2), (0,))


STREAMING_MODULES = (
    "streaming.py",
    "pacing.py",
    "following.py",
    "rest_detection.py",
    "stopping.py",
    "point_messages.py",
    "joint_text.py",
    "move_result.py",
)


@pytest.mark.parametrize("module", STREAMING_MODULES)
def test_streaming_does_not_import_the_client(module: str) -> None:
    tree = ast.parse((CLIENT / module).read_text(encoding="utf-8"))
    modules = {
        node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module
    }
    assert "pymotoros.client.robot" not in modules
    assert "time" not in {
        alias.name
        for node in ast.walk(tree)
        if isinstance(node, ast.Import)
        for alias in node.names
    }
