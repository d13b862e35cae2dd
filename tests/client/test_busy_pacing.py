"""Issue 22: the paced first offer sends about one offer per point, and the robot's
motion is the same, tick for tick, as with the immediate offer it replaced.

Each case streams the same plan to a fresh twin twice, once per
:class:`~pymotoros.client.streaming.BusyPolicy`, and records, on the twin's side, the
commanded pulses after every controller tick and the tick at which each point was
accepted. Both must be identical: MotoROS takes a pending point at the first tick
after it was accepted, so the same acceptance tick gives the same increments.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from pymotoros.client.motion_port import MotionPort, MotionReadiness
from pymotoros.client.streaming import BusyPolicy, StreamStats, TrajectoryStreamer
from pymotoros.protocol.constants import ResultCode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionReply, WireMessage
from pymotoros.testing import Twin, twin

GOAL = (0.5, 0.3, 0.2, 0.1, -0.6, 0.3)
SPEED_SCALE = 0.1
"""A move of about 2.3 s from the HC10's home: long enough for the queue to fill past the
client's keep-ahead (0.2 s), short enough to stream at 4 ms in a fraction of a second."""


@dataclass
class AcceptanceLog:
    """A motion port that notes the controller tick at which each point was accepted."""

    port: MotionPort
    cell: Twin
    ticks: list[int] = field(default_factory=list)

    async def request_motion(
        self, message: WireMessage, *, timeout_s: float | None = None
    ) -> MotoMotionReply:
        reply = await self.port.request_motion(message, timeout_s=timeout_s)
        if isinstance(message, JointTrajPtFull) and reply.result == ResultCode.SUCCESS:
            self.ticks.append(self.cell.controller.tick_count)
        return reply

    async def queue_count(self, group: int = 0) -> int:
        return await self.port.queue_count(group)

    async def check_motion_ready(self) -> MotionReadiness:
        return await self.port.check_motion_ready()


@dataclass(frozen=True)
class Run:
    pulses: list[tuple[int, tuple[int, ...]]]
    """(controller tick, commanded pulses after it) for every tick of the move."""
    accepted_at: list[int]
    """The controller tick count when each point was accepted."""
    stream: StreamStats


async def stream(spacing_s: float, policy: BusyPolicy, speed_scale: float = SPEED_SCALE) -> Run:
    async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
        await client.enable()
        here = await client.current_positions()
        plan = client.plan(here, GOAL, speed_scale=speed_scale, sample_period=spacing_s)
        log = AcceptanceLog(client.streamer.port, cell)
        streamer = TrajectoryStreamer(
            log,
            client.streamer.states,
            client.robot,
            client.controller,
            clock=cell.clock,
            busy_policy=policy,
        )
        pulses: list[tuple[int, tuple[int, ...]]] = []
        remove = cell.on_tick(
            lambda: pulses.append((cell.controller.tick_count, cell.commanded_pulses(0)))
        )
        try:
            result = await streamer.execute(plan, (0,))
        finally:
            remove()
        assert result.stream.points == len(plan.points)
        return Run(pulses, log.ticks, result.stream)


@pytest.mark.parametrize("spacing_s", [0.1, 0.02, 0.004])
async def test_paced_offers_give_the_same_motion_with_about_one_offer_per_point(
    spacing_s: float,
) -> None:
    immediate = await stream(spacing_s, BusyPolicy.IMMEDIATE)
    paced = await stream(spacing_s, BusyPolicy.PACED)
    assert paced.accepted_at == immediate.accepted_at
    assert len(paced.pulses) == len(immediate.pulses)
    assert paced.pulses == immediate.pulses
    points = paced.stream.points
    assert paced.stream.offers <= 1.1 * points  # about once per point …
    assert immediate.stream.offers >= 1.9 * points  # … where each took two to five


async def test_points_behind_a_full_queue_still_meet_busy_and_move_the_same() -> None:
    """Points 1 s apart on a 4.5 s move (250 increments: more than the 200-entry queue,
    §5.1): MotoROS keeps the pending slot for many ticks, so even paced offers meet
    BUSY; the retries run as before and take each point at the same tick."""
    immediate = await stream(1.0, BusyPolicy.IMMEDIATE, speed_scale=0.05)
    paced = await stream(1.0, BusyPolicy.PACED, speed_scale=0.05)
    assert paced.stream.busy_replies > 0
    assert paced.accepted_at == immediate.accepted_at
    assert paced.pulses == immediate.pulses
    assert paced.stream.offers < immediate.stream.offers
