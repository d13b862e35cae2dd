"""Issue 21 "Done when", over TCP: a client that does not know the workspace (a plain
``RobotClient``: no cell, so no check before the move) drives the robot into an obstacle
of the simulator's cell, served by :class:`SimulatorApp` on 127.0.0.1 port 0.

A GP7 (no PFL) gets alarm 4315 COLLISION DETECT with servo power off, an HC10 the PFL
refusal (NOT_READY 5011); both stop at the obstacle, at most one tick's travel into it.
The in-memory twin's versions are in tests/controller/test_workspace_contact.py.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from dataclasses import dataclass

import pytest

from contact_depth import commanded_joints, depth_and_one_tick
from pymotoros.client import NotReadyError, Ports, RobotClient
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.controller.safety.contact import COLLISION_ALARM, COLLISION_ALARM_TEXT
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.runtime.app import SimulatorApp

from .support import LOCAL

GOAL = (0.0, 1.0, 0.0, 0.0, 0.0, 0.0)
"""L tilts the arm forward: each ball sits where the arm passes halfway there."""
BALLS = {"gp7": [0.75, 0.0, 0.55], "hc10": [0.45, 0.0, 0.75]}


def _controller(robot: str) -> VirtualController:
    return VirtualController(
        cell_from_dict(
            {
                "controller": {"model": "yrc1000"},
                "robot": {"model": robot},
                "workspace": {"obstacles": [{"name": "ball", "sphere": 0.1, "xyz": BALLS[robot]}]},
            }
        )
    )


def _plain_client(sim: SimulatorApp, robot: str) -> RobotClient:
    """A client that knows the robot model but not the cell (no obstacles)."""
    ports = sim.ports
    return RobotClient(
        "127.0.0.1",
        ports=Ports(ports.motion, ports.state, ports.io),
        controller="yrc1000",
        robot=robot,
        timeout_s=5.0,
    )


@dataclass
class Driven:
    """A robot a plain client drove towards GOAL, through the ball: the move was refused."""

    client: RobotClient
    controller: VirtualController
    refusal: NotReadyError


@pytest.fixture
async def driven(request: pytest.FixtureRequest) -> AsyncIterator[Driven]:
    """The simulator serving the robot ``request.param`` with the ball in its cell, and a
    plain client whose move towards GOAL was refused (the client stays connected)."""
    controller = _controller(request.param)
    async with SimulatorApp(controller, LOCAL) as sim, _plain_client(sim, request.param) as client:
        await client.wait_for_state(5.0)
        await client.enable()
        with pytest.raises(NotReadyError) as info:
            await client.move_joints(GOAL, speed_scale=0.5)
        yield Driven(client, controller, info.value)


@pytest.mark.parametrize("driven", ["gp7"], indirect=True)
async def test_a_gp7_driven_into_an_obstacle_gets_the_collision_alarm_over_tcp(
    driven: Driven,
) -> None:
    client, controller = driven.client, driven.controller
    assert driven.refusal.reason is NotReadySubcode.ALARM
    snapshot = controller.snapshot()
    assert [(a.code, a.text, a.subcode) for a in snapshot.alarms] == [
        (COLLISION_ALARM, COLLISION_ALARM_TEXT, 1)
    ]
    assert not snapshot.servo
    touched = controller.workspace_contacts
    assert {c.obstacle for c in touched} == {"ball"}
    assert {c.link for c in touched} == {"link_6_t"}  # the wrist meets it first
    depth, one_tick = depth_and_one_tick(controller.cell, controller)
    assert 0.0 < depth <= one_tick  # stopped at the ball, not through it
    assert 0.2 < commanded_joints(controller)[1] < 0.8  # far from the goal
    # the client's feedback says the same: the robot stands where it stopped
    here = await client.current_positions(timeout_s=5.0)
    assert here[1] == pytest.approx(commanded_joints(controller)[1], abs=1e-3)
    # START_TRAJ_MODE resets the alarm and powers the servos; backing out is allowed
    await client.enable()
    await client.move_joints((0.0,) * 6, speed_scale=0.5)
    assert not controller.snapshot().alarms
    assert controller.workspace_contacts == ()


@pytest.mark.parametrize("driven", ["hc10"], indirect=True)
async def test_an_hc10_driven_into_an_obstacle_gets_the_pfl_refusal_over_tcp(
    driven: Driven,
) -> None:
    controller = driven.controller
    assert driven.refusal.reason is NotReadySubcode.PFL_ACTIVE
    snapshot = controller.snapshot()
    assert snapshot.pfl == "stop"
    assert snapshot.servo  # PFL stops the robot; servo power stays on
    assert not snapshot.alarms
    assert [(c.obstacle, c.link) for c in controller.workspace_contacts] == [("ball", "link_2_l")]
    depth, one_tick = depth_and_one_tick(controller.cell, controller)
    assert 0.0 < depth <= one_tick
    assert 0.3 < commanded_joints(controller)[1] < 0.7
