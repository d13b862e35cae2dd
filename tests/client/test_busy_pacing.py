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
from pathlib import Path

import pytest

from pymotoros.client.motion_port import MotionPort, MotionReadiness
from pymotoros.client.streaming import BusyPolicy, StreamStats, TrajectoryStreamer
from pymotoros.controller.cell import load_cell
from pymotoros.protocol.constants import ResultCode
from pymotoros.protocol.messages import (
    JointTrajPtFull,
    MotoJointTrajPtFullEx,
    MotoMotionReply,
    WireMessage,
)
from pymotoros.testing import Twin, twin

GOAL = (0.5, 0.3, 0.2, 0.1, -0.6, 0.3)
SPEED_SCALE = 0.1
"""A move of about 2.3 s from the HC10's home: long enough for the queue to fill past the
client's keep-ahead (0.2 s), short enough to stream at 4 ms in a fraction of a second."""
TWO_ARMS = Path(__file__).resolve().parents[2] / "examples" / "cells" / "two_hc10_dx100.toml"
"""Two HC10 on a DX100: both groups in one JOINT_TRAJ_PT_FULL_EX per point."""


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
        point = isinstance(message, JointTrajPtFull | MotoJointTrajPtFullEx)
        if point and reply.result == ResultCode.SUCCESS:
            self.ticks.append(self.cell.controller.tick_count)
        return reply

    async def queue_count(self, group: int = 0) -> int:
        return await self.port.queue_count(group)

    async def check_motion_ready(self) -> MotionReadiness:
        return await self.port.check_motion_ready()


@dataclass(frozen=True)
class Run:
    pulses: list[tuple[int, tuple[tuple[int, ...], ...]]]
    """(controller tick, every group's commanded pulses after it) for every tick."""
    accepted_at: list[int]
    """The controller tick count when each point was accepted."""
    stream: StreamStats


async def stream(
    spacing_s: float,
    policy: BusyPolicy,
    *,
    speed_scale: float = SPEED_SCALE,
    two_arms: bool = False,
) -> Run:
    cell_config = load_cell(TWO_ARMS) if two_arms else None
    robot = None if two_arms else "hc10"
    async with twin(robot, cell=cell_config, timeout_s=2.0) as (client, cell):
        await client.enable()
        groups = (0, 1) if two_arms else (0,)
        here: tuple[float, ...] = ()
        for g in groups:
            here += await client.current_positions(g)
        goal = GOAL * len(groups)
        plan = client.plan(
            here, goal, groups=groups, speed_scale=speed_scale, sample_period=spacing_s
        )
        log = AcceptanceLog(client.streamer.port, cell)
        streamer = TrajectoryStreamer(
            log,
            client.streamer.states,
            client.robot,
            client.controller,
            clock=cell.clock,
            busy_policy=policy,
        )
        pulses: list[tuple[int, tuple[tuple[int, ...], ...]]] = []

        def record() -> None:
            commanded = tuple(cell.commanded_pulses(g) for g in groups)
            pulses.append((cell.controller.tick_count, commanded))

        remove = cell.on_tick(record)
        try:
            result = await streamer.execute(plan, groups)
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


async def test_two_groups_in_one_message_move_the_same_with_one_offer_per_point() -> None:
    """JOINT_TRAJ_PT_FULL_EX: one sequence for both groups, each with its pending slot
    (§3.5); both slots free at the same tick, so the pacing is the same."""
    immediate = await stream(0.02, BusyPolicy.IMMEDIATE, two_arms=True)
    paced = await stream(0.02, BusyPolicy.PACED, two_arms=True)
    assert paced.accepted_at == immediate.accepted_at
    assert paced.pulses == immediate.pulses
    assert paced.stream.offers <= 1.1 * paced.stream.points
    assert immediate.stream.offers >= 1.9 * immediate.stream.points
