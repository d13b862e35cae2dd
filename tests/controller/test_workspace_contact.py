"""Contact in the twin: a robot driven into an obstacle of the cell stops at it.

An HC robot with PFL gets a PFL contact (the client sees NOT_READY 5011), a link pinned
between two obstacles a clamping (PFL escape backs it off); any other robot gets alarm
4315 COLLISION DETECT with servo power off (the client sees 5001). On the in-memory
twin (virtual time) and over TCP against ``pymotoros sim --config``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

from contact_depth import commanded_joints, depth_and_one_tick
from pymotoros.client import NotReadyError, RobotClient, SyncRobotClient
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.controller.safety.contact import COLLISION_ALARM, is_clamping
from pymotoros.kinematics.collision import CollisionWorld, Contact
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.testing import twin

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import running_sim

# L tilts the arm forward; each ball sits where the arm passes halfway there
GOAL = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]
HOME = [0.0] * 6
HC10_BALL = [0.45, 0.0, 0.75]
GP7_BALL = [0.75, 0.0, 0.55]


def _cell(robot: str, obstacles: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "name": f"{robot} with obstacles",
        "controller": {"model": "yrc1000"},
        "robot": {"model": robot},
        "workspace": {"obstacles": obstacles},
    }


def _ball(xyz: list[float], name: str = "ball") -> dict[str, Any]:
    return {"name": name, "sphere": 0.1, "xyz": xyz}


async def _move_refused(robot: RobotClient) -> NotReadyError:
    """Enable and move towards GOAL: an obstacle on the way, the move is refused."""
    await robot.enable()
    with pytest.raises(NotReadyError) as info:
        await robot.move_joints(GOAL, speed_scale=0.5)
    return info.value


async def test_an_hc10_driven_into_an_obstacle_gets_the_pfl_refusal_and_stops_at_it() -> None:
    cell = cell_from_dict(_cell("hc10", [_ball(HC10_BALL)]))
    async with twin(cell=cell) as (robot, the_twin):
        assert (await _move_refused(robot)).reason is NotReadySubcode.PFL_ACTIVE
        controller = the_twin.controller
        assert controller.snapshot().pfl == "stop"
        touched = controller.workspace_contacts
        assert [(c.obstacle, c.link) for c in touched] == [("ball", "link_2_l")]
        depth, one_tick = depth_and_one_tick(cell, controller)
        assert 0.0 < depth <= one_tick
        assert 0.3 < commanded_joints(controller)[1] < 0.7  # stopped on the way, at the ball
        # moving out of the contact is allowed once PFL has cleared
        await the_twin.sleep(1.0)
        await robot.enable()
        await robot.move_joints(HOME, speed_scale=0.5)
        assert max(abs(v) for v in commanded_joints(controller)) < 1e-3
        assert controller.workspace_contacts == ()


async def test_a_gp7_gets_the_collision_alarm_with_servo_off() -> None:
    cell = cell_from_dict(_cell("gp7", [_ball(GP7_BALL)]))
    async with twin(cell=cell) as (robot, the_twin):
        assert (await _move_refused(robot)).reason is NotReadySubcode.ALARM
        snapshot = the_twin.controller.snapshot()
        alarms = [(a.code, a.text) for a in snapshot.alarms]
        assert alarms == [(COLLISION_ALARM, "COLLISION DETECT")]
        assert snapshot.alarms[0].subcode == 1  # R1
        assert not snapshot.servo
        depth, one_tick = depth_and_one_tick(cell, the_twin.controller)
        assert 0.0 < depth <= one_tick
        # START_TRAJ_MODE resets the alarm and powers the servos; backing out is allowed
        await robot.enable()
        await robot.move_joints(HOME, speed_scale=0.5)
        assert not the_twin.controller.snapshot().alarms


async def test_a_link_pinned_between_two_obstacles_is_a_clamping_and_backs_off() -> None:
    x, _, z = HC10_BALL
    pair = [_ball([x, 0.12, z], "left"), _ball([x, -0.12, z], "right")]
    cell = cell_from_dict(_cell("hc10", pair))
    async with twin(cell=cell) as (robot, the_twin):
        await _move_refused(robot)
        controller = the_twin.controller
        assert is_clamping(controller.workspace_contacts)
        stopped = commanded_joints(controller)[1]
        phases = {controller.snapshot().pfl}
        for _ in range(100):  # 1.2 s: the stop, then the escape
            await the_twin.sleep(0.012)
            phases.add(controller.snapshot().pfl)
        assert {"stop", "escape", "idle"} <= phases
        assert commanded_joints(controller)[1] < stopped  # backed off along its path
        world = CollisionWorld(cell.groups, cell.workspace)
        assert world.contacts([commanded_joints(controller)]) == []


def test_is_clamping_needs_one_link_on_two_obstacles() -> None:
    a = Contact("left", "link_2_l", "R1", -0.001)
    assert not is_clamping([a])
    assert not is_clamping([a, Contact("left", "link_3_u", "R1", -0.001)])
    assert is_clamping([a, Contact("right", "link_2_l", "R1", -0.001)])


def test_a_cell_without_obstacles_has_no_contact_check() -> None:
    controller = VirtualController(cell_from_dict(_cell("hc10", [])))
    assert controller._workspace.contact is None
    assert controller.workspace_contacts == ()


def _cell_file(tmp_path: Path, robot: str, ball: list[float]) -> Path:
    path = tmp_path / f"{robot}.toml"
    x, y, z = ball
    path.write_text(
        f'[controller]\nmodel = "yrc1000"\n[robot]\nmodel = "{robot}"\n'
        f'[[workspace.obstacles]]\nname = "ball"\nsphere = 0.1\nxyz = [{x}, {y}, {z}]\n',
        encoding="utf-8",
    )
    return path


@pytest.mark.parametrize(
    ("robot", "ball", "reason"),
    [
        ("hc10", HC10_BALL, NotReadySubcode.PFL_ACTIVE),
        ("gp7", GP7_BALL, NotReadySubcode.ALARM),
    ],
)
def test_over_tcp(tmp_path: Path, robot: str, ball: list[float], reason: NotReadySubcode) -> None:
    with (
        running_sim("--config", str(_cell_file(tmp_path, robot, ball))) as sim,
        SyncRobotClient(**sim.client_options()) as client,
    ):
        client.enable()
        with pytest.raises(NotReadyError) as info:
            client.move_joints(GOAL, speed_scale=0.5)
        assert info.value.reason is reason
        state = sim.api("/api/state")
        position = client.current_positions()
        assert 0.2 < position[1] < 0.8  # stopped at the ball, far from the goal
        if robot == "gp7":
            assert [a["code"] for a in state["alarms"]] == [COLLISION_ALARM]
            assert state["servo"] is False


async def test_an_obstacle_put_at_run_time_stops_the_robot_and_shows_in_the_state() -> None:
    cell = cell_from_dict(_cell("hc10", []))
    async with twin(cell=cell) as (robot, the_twin):
        controller = the_twin.controller
        assert controller._workspace.contact is None
        controller.put_obstacle({"name": "person", "sphere": 0.1, "xyz": HC10_BALL})
        assert (await _move_refused(robot)).reason is NotReadySubcode.PFL_ACTIVE
        state = controller.workspace_state()
        assert state["obstacles"] == [
            {"name": "person", "sphere": 0.1, "xyz": HC10_BALL, "rpy_deg": [0.0, 0.0, 0.0]}
        ]
        contacts = state["contacts"]
        assert isinstance(contacts, list)
        assert [(c["obstacle"], c["link"]) for c in contacts] == [("person", "link_2_l")]
        # the person steps aside: the move goes through where they stood
        controller.remove_obstacle("person")
        assert controller._workspace.contact is None
        await the_twin.sleep(1.0)
        await robot.enable()
        await robot.move_joints(GOAL, speed_scale=0.5)
        assert commanded_joints(controller)[1] == pytest.approx(1.0, abs=1e-3)


async def test_moving_an_obstacle_by_name_moves_the_check_with_it() -> None:
    cell = cell_from_dict(_cell("gp7", [_ball([3.0, 3.0, 3.0])]))
    async with twin(cell=cell) as (robot, the_twin):
        controller = the_twin.controller
        await robot.enable()
        await robot.move_joints([0.0, 0.2, 0.0, 0.0, 0.0, 0.0], speed_scale=0.5)
        controller.put_obstacle({"name": "ball", "sphere": 0.1, "xyz": GP7_BALL})
        assert [o.name for o in controller.obstacles] == ["ball"]
        with pytest.raises(NotReadyError) as info:
            await robot.move_joints(GOAL, speed_scale=0.5)
        assert info.value.reason is NotReadySubcode.ALARM


def test_a_bad_obstacle_at_run_time_names_its_key() -> None:
    from pymotoros.errors import ConfigError

    controller = VirtualController(cell_from_dict(_cell("hc10", [])))
    with pytest.raises(ConfigError, match=r"^obstacle\.box: must be three"):
        controller.put_obstacle({"name": "t", "box": [1, 1], "xyz": [0, 0, 0]})
    with pytest.raises(ConfigError, match="no obstacle named 'nope'"):
        controller.remove_obstacle("nope")
    assert controller.obstacles == ()


async def test_an_obstacle_put_against_a_robot_at_rest_is_no_contact_until_it_moves_in() -> None:
    cell = cell_from_dict(_cell("gp7", []))
    async with twin(cell=cell) as (robot, the_twin):
        controller = the_twin.controller
        await robot.enable()
        await robot.move_joints([0.0, 0.4, 0.0, 0.0, 0.0, 0.0], speed_scale=0.5)
        # a box pressed against the wrist from the front while the arm stands still
        controller.put_obstacle({"name": "box", "box": [0.2, 0.6, 0.6], "xyz": [0.8, 0.0, 0.55]})
        assert controller.workspace_contacts  # touching, at rest
        await the_twin.sleep(0.1)
        assert not controller.snapshot().alarms
        # backing away is allowed; leaning further in is a collision
        await robot.move_joints([0.0, 0.1, 0.0, 0.0, 0.0, 0.0], speed_scale=0.5)
        assert not controller.snapshot().alarms
        with pytest.raises(NotReadyError):
            await robot.move_joints([0.0, 0.6, 0.0, 0.0, 0.0, 0.0], speed_scale=0.5)
        assert [a.code for a in controller.snapshot().alarms] == [COLLISION_ALARM]
