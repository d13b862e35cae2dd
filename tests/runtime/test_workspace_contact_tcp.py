"""Issue 21 "Done when", over TCP: a client that does not know the workspace (a plain
``RobotClient``: no cell, so no check before the move) drives the robot into an obstacle
of the simulator's cell, served by :class:`SimulatorApp` on 127.0.0.1 port 0.

A GP7 (no PFL) gets alarm 4315 COLLISION DETECT with servo power off, an HC10 the PFL
refusal (NOT_READY 5011); both stop at the obstacle, at most one tick's travel into it.
The in-memory twin's versions are in tests/controller/test_workspace_contact.py.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from operator import mul
from typing import Any

import pytest

from pymotoros.client import NotReadyError, Ports, RobotClient
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.controller.safety.contact import COLLISION_ALARM, COLLISION_ALARM_TEXT
from pymotoros.kinematics.collision import CollisionWorld
from pymotoros.motion import GroupAxes, from_pulses
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


def _joints(controller: VirtualController) -> list[float]:
    axes = GroupAxes.from_model(controller.cell.groups[0], controller.cell.controller)
    return list(from_pulses(controller.commanded_pulses(0), axes)[: axes.num_axes])


def _depth_and_one_tick(controller: VirtualController) -> tuple[float, float]:
    """How deep the commanded robot is in the ball, and the farthest one tick at full
    speed can carry any point of it (each joint's largest increment × its reach)."""
    cell = controller.cell
    world = CollisionWorld(cell.groups, cell.workspace)
    _, contacts = world.probe([_joints(controller)])
    depth = max((-c.distance_m for c in contacts), default=0.0)
    axes = GroupAxes.from_model(cell.groups[0], cell.controller)
    reach = world.joint_reach(0)
    per_slot = [0.0] * 8
    for k in range(axes.num_axes):
        slot = axes.ros_to_slot[k]
        per_slot[slot] = reach[k] / axes.pulses_per_unit[slot]
    return depth, sum(map(mul, axes.max_increment, per_slot))


@pytest.fixture
async def served(request: pytest.FixtureRequest) -> AsyncIterator[tuple[SimulatorApp, Any]]:
    controller = _controller(request.param)
    async with SimulatorApp(controller, LOCAL) as sim:
        yield sim, controller


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


@pytest.mark.parametrize("served", ["gp7"], indirect=True)
async def test_a_gp7_driven_into_an_obstacle_gets_the_collision_alarm_over_tcp(
    served: tuple[SimulatorApp, VirtualController],
) -> None:
    sim, controller = served
    async with _plain_client(sim, "gp7") as client:
        await client.wait_for_state(5.0)
        await client.enable()
        with pytest.raises(NotReadyError) as info:
            await client.move_joints(GOAL, speed_scale=0.5)
        assert info.value.reason is NotReadySubcode.ALARM
        snapshot = controller.snapshot()
        assert [(a.code, a.text, a.subcode) for a in snapshot.alarms] == [
            (COLLISION_ALARM, COLLISION_ALARM_TEXT, 1)
        ]
        assert not snapshot.servo
        touched = controller.workspace_contacts
        assert {c.obstacle for c in touched} == {"ball"}
        assert {c.link for c in touched} == {"link_6_t"}  # the wrist meets it first
        depth, one_tick = _depth_and_one_tick(controller)
        assert 0.0 < depth <= one_tick  # stopped at the ball, not through it
        assert 0.2 < _joints(controller)[1] < 0.8  # far from the goal
        # the client's feedback says the same: the robot stands where it stopped
        here = await client.current_positions(timeout_s=5.0)
        assert here[1] == pytest.approx(_joints(controller)[1], abs=1e-3)
        # START_TRAJ_MODE resets the alarm and powers the servos; backing out is allowed
        await client.enable()
        await client.move_joints((0.0,) * 6, speed_scale=0.5)
        assert not controller.snapshot().alarms
        assert controller.workspace_contacts == ()


@pytest.mark.parametrize("served", ["hc10"], indirect=True)
async def test_an_hc10_driven_into_an_obstacle_gets_the_pfl_refusal_over_tcp(
    served: tuple[SimulatorApp, VirtualController],
) -> None:
    sim, controller = served
    async with _plain_client(sim, "hc10") as client:
        await client.wait_for_state(5.0)
        await client.enable()
        with pytest.raises(NotReadyError) as info:
            await client.move_joints(GOAL, speed_scale=0.5)
        assert info.value.reason is NotReadySubcode.PFL_ACTIVE
        snapshot = controller.snapshot()
        assert snapshot.pfl == "stop"
        assert snapshot.servo  # PFL stops the robot; servo power stays on
        assert not snapshot.alarms
        assert [(c.obstacle, c.link) for c in controller.workspace_contacts] == [
            ("ball", "link_2_l")
        ]
        depth, one_tick = _depth_and_one_tick(controller)
        assert 0.0 < depth <= one_tick
        assert 0.3 < _joints(controller)[1] < 0.7
