"""A motion connection lost mid-move, then our client connects again (docs/client.md).

MotoROS 1.9.12 keeps the queued increments when the motion connection closes, and the
next connection, whoever opens it, resumes them (§2.2; the twin's fidelity exact). Our
client sends STOP_MOTION the moment its motion connection opens, so the remainder of the
lost trajectory does not run under it; it then plans from the feedback at rest.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Sequence

import pytest

from pymotoros.client import ConnectionLostError
from pymotoros.protocol.constants import TCP_PORT_MOTION
from pymotoros.testing import Twin, twin

GOAL = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
TICK_TRAVEL_RAD = 0.02
"""More than the arm travels in the few ticks between the connect and the STOP_MOTION
(at most a couple of 4 ms periods at this move's speed, ~0.5 rad/s)."""


def distance(a: Sequence[float], b: Sequence[float]) -> float:
    return math.dist(a[:6], b[:6])


async def lose_motion_connection_mid_move(the_twin: Twin, speed_scale: float) -> None:
    """Start a move with a client of ``the_twin``, reset its motion connection once
    increments are queued and the arm has moved, and see the client fail."""
    async with the_twin.client() as client:
        await client.wait_for_state()
        await client.enable()
        move = asyncio.create_task(client.move_joints(GOAL, speed_scale=speed_scale))
        for _ in range(10_000):  # bounded: virtual time, a few seconds of motion at most
            moved = the_twin.controller.snapshot().groups[0].command_rad[0]
            if moved > 0.2 and the_twin.controller.has_queued_motion():
                break
            await the_twin.sleep(0.004)
        else:
            pytest.fail("the move never got under way")
        the_twin.motion.drop_clients()  # a connection reset, as a cable pulled
        with pytest.raises(ConnectionLostError):
            await move


@pytest.mark.parametrize("fidelity", ["exact", "safe"])
async def test_reconnecting_client_stops_the_lost_moves_remainder(fidelity: str) -> None:
    async with Twin(fidelity=fidelity) as the_twin:
        await lose_motion_connection_mid_move(the_twin, speed_scale=0.2)
        controller = the_twin.controller
        # exact: the lost trajectory's increments wait in the queue (MotoROS 1.9.12);
        # safe: cleared at the close
        assert controller.has_queued_motion() is (fidelity == "exact")
        await the_twin.sleep(0.5)  # nobody connected: nothing runs them
        lost_at = list(controller.snapshot().groups[0].command_rad)
        assert distance(lost_at, GOAL) > 0.2
        async with the_twin.client() as client:  # connecting sends STOP_MOTION at once
            await client.wait_for_state()
            assert not controller.has_queued_motion()
            at_rest = await client.current_positions()  # waits for rest
            await the_twin.sleep(1.0)  # had the queue run, the arm would be far along now
            after = list(controller.snapshot().groups[0].command_rad)
            assert distance(after, lost_at) < TICK_TRAVEL_RAD, (lost_at, after)
            assert distance(at_rest, after) < 1e-3
            # and the client moves on from there, to the goal
            await client.enable()
            result = await client.move_joints(GOAL, speed_scale=0.5)
            assert distance(result.final_positions, GOAL) < 1e-3
        # stopping at once is what a robot needs: the client lint has nothing to say
        # about the reconnect (docs/sim.md, reconnect-resumed-motion)
        assert [str(f.code) for f in the_twin.lint.findings()] == []


async def test_without_the_stop_a_new_connection_resumes_the_lost_motion() -> None:
    """The hazard the client's STOP_MOTION guards against: in exact, a connection that
    sends nothing makes the robot resume the lost trajectory (§2.2)."""
    async with Twin(fidelity="exact") as the_twin:
        await lose_motion_connection_mid_move(the_twin, speed_scale=0.2)
        controller = the_twin.controller
        lost_at = list(controller.snapshot().groups[0].command_rad)
        _reader, writer = await the_twin.connect("bystander", TCP_PORT_MOTION)
        try:
            await the_twin.sleep(1.0)
            moved = list(controller.snapshot().groups[0].command_rad)
            assert distance(moved, lost_at) > 0.05  # the robot moved for a silent client
            assert not controller.has_queued_motion()  # the whole queue ran
        finally:
            writer.close()
        await the_twin.sleep(0.1)  # decided at its close: it never sent STOP_MOTION
        codes = [str(f.code) for f in the_twin.lint.findings()]
        assert "reconnect-resumed-motion" in codes  # the client lint says so


async def test_twin_default_is_exact() -> None:
    async with twin() as (_client, the_twin):
        assert the_twin.cell.fidelity == "exact"
        assert the_twin.motion.fidelity == "exact"
