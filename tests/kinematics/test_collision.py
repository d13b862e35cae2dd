"""The collision checker: capsules per link, obstacles, self-collision, the clearance bound."""

from __future__ import annotations

import dataclasses
import math

import coal
import numpy as np
import pytest

from pymotoros.kinematics import chain_for
from pymotoros.kinematics.collision import NEAR_M, CollisionWorld, link_name
from pymotoros.models import ROBOTS, robot_model
from pymotoros.models.robots import GroupKind, Transform
from pymotoros.models.workspace import EMPTY_WORKSPACE, Workspace, workspace_from_dict


def _world(robot: str, obstacles: list[dict[str, object]], **extra: object) -> CollisionWorld:
    model = robot_model(robot)
    names = [g.name for g in model.groups]
    ws = workspace_from_dict({"obstacles": obstacles, **extra}, "test", names)
    return CollisionWorld(model.groups, ws)


def _zeros(robot: str) -> list[list[float]]:
    return [[0.0] * g.num_axes for g in robot_model(robot).groups]


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_every_robot_group_has_shapes_and_none_collide_at_zero_or_home(robot: str) -> None:
    model = robot_model(robot)
    world = CollisionWorld(model.groups, EMPTY_WORKSPACE)
    for group, body in zip(model.groups, world.bodies, strict=True):
        assert (body is not None) == (group.kind is GroupKind.ROBOT)
        assert len(group.link_radii) == (group.num_axes + 1 if body is not None else 0)
        if body is not None:  # a capsule per link, base link first
            radii = {p.order: p.radius for p in body.parts if p.order <= group.num_axes}
            assert [radii[i] for i in range(len(radii))] == list(group.link_radii)
    assert world.self_contacts(_zeros(robot)) == []
    assert world.self_contacts([list(g.home) for g in model.groups]) == []
    assert world.probe(_zeros(robot)) == (math.inf, [])


def test_link_names_follow_ros_industrial() -> None:
    assert link_name("joint_1_s") == "link_1_s"
    assert link_name("joint_t") == "link_t"
    assert link_name("arm_left_joint_2_l") == "arm_left_link_2_l"


@pytest.mark.parametrize(
    ("robot", "q", "pair"),
    [
        # the arm swung down beside its own base
        ("gp7", [-1.56, 1.83, -0.73, -0.02, 0.13, -6.17], ("base_link", "link_3_u")),
        ("hc10", [-1.13, -2.4, 5.66, -2.15, 1.49, 1.0], ("base_link", "link_3_u")),
    ],
)
def test_self_collision_names_both_links(robot: str, q: list[float], pair: tuple[str, str]) -> None:
    world = _world(robot, [])
    found = {(c.obstacle, c.link) for c in world.self_contacts([q])}
    assert pair in found
    assert all(c.self_collision and c.distance_m <= 0 for c in world.self_contacts([q]))


def test_a_ball_at_the_flange_touches_the_last_link_and_the_tool() -> None:
    flange = chain_for("hc10").position(np.zeros(6), "tool0")
    world = _world("hc10", [{"name": "ball", "sphere": 0.02, "xyz": [*flange]}])
    clearance, contacts = world.probe([[0.0] * 6])
    assert clearance < 0
    assert {c.link for c in contacts} >= {"link_6_t"}
    assert all(c.obstacle == "ball" and c.group == "R1" for c in contacts)
    # a 150 mm tool reaches a ball below the flange that the bare arm misses
    below = flange + np.array([0.0, 0.0, -0.13])
    world = _world("hc10", [{"name": "ball", "sphere": 0.02, "xyz": [*below]}])
    assert world.contacts([[0.0] * 6]) == []
    world.set_tool(0, Transform((0.0, 0.0, 0.15)))
    assert [c.link for c in world.contacts([[0.0] * 6])] == ["tool"]


def test_the_base_link_does_not_touch_what_it_stands_on() -> None:
    world = _world("hc10", [{"name": "table", "box": [1.2, 0.8, 0.05], "xyz": [0.6, 0.0, -0.025]}])
    clearance, contacts = world.probe([[0.0] * 6])
    assert contacts == []
    assert clearance > 0


def test_orientation_of_a_box_counts() -> None:
    # a bar 0.4 m beside the upright arm: along x it misses, turned 90° about z it reaches in
    bar = {"name": "bar", "box": [0.8, 0.04, 0.04], "xyz": [0.0, 0.4, 0.6]}
    assert _world("hc10", [bar]).contacts([[0.0] * 6]) == []
    turned = {**bar, "rpy_deg": [0, 0, 90]}
    assert "link_2_l" in {c.link for c in _world("hc10", [turned]).contacts([[0.0] * 6])}


def _exact_min(world: CollisionWorld, q: list[float]) -> float:
    body = world.bodies[0]
    assert body is not None
    best = math.inf
    for part in body.place(q):
        if not part.joint:
            continue
        for obstacle in world._obstacles:
            d = coal.distance(
                part.geometry,
                coal.Transform3s(body.world_of(part)),
                obstacle.geometry,
                obstacle.transform,
                coal.DistanceRequest(),
                coal.DistanceResult(),
            )
            best = min(best, float(d))
    return best


def test_the_clearance_is_a_lower_bound_and_exact_near_the_robot() -> None:
    obstacles: list[dict[str, object]] = [
        {"name": "table", "box": [1.2, 0.8, 0.05], "xyz": [0.6, 0.0, -0.03]},
        {"name": "post", "cylinder": [0.05, 1.5], "xyz": [0.5, -0.4, 0.75], "rpy_deg": [10, 0, 0]},
        {"name": "ball", "sphere": 0.1, "xyz": [0.4, 0.3, 0.5]},
    ]
    world = _world("hc10", obstacles)
    rng = np.random.default_rng(7)
    group = robot_model("hc10").groups[0]
    for _ in range(60):
        q = [float(rng.uniform(a.lower, a.upper)) for a in group.axes]
        clearance, contacts = world.probe([q])
        exact = _exact_min(world, q)
        assert clearance <= exact + 1e-9
        if exact <= NEAR_M:
            assert clearance == pytest.approx(exact, abs=1e-9)
        assert bool(contacts) == (exact <= 0.0)


def test_joint_reach_bounds_how_far_any_part_moves() -> None:
    world = _world("gp7", [{"name": "far", "sphere": 0.1, "xyz": [5, 5, 5]}])
    world.set_tool(0, Transform((0.0, 0.0, 0.2)))
    body = world.bodies[0]
    assert body is not None
    reach = world.joint_reach(0)
    rng = np.random.default_rng(3)
    for _ in range(40):
        q = rng.uniform(-1.5, 1.5, 6)
        dq = rng.uniform(-0.01, 0.01, 6)
        before = [np.array(p.center) for p in body.place(q)]
        after = [np.array(p.center) for p in body.place(q + dq)]
        bound = float(np.dot(np.abs(dq), reach))
        moved = max(float(np.linalg.norm(a - b)) for a, b in zip(after, before, strict=True))
        assert moved <= bound


def test_an_obstacle_in_another_groups_frame() -> None:
    # two HC10s, R2 standing 2 m along x and turned to face R1; the ball is given in R2's
    # frame, 0.45 m in front of it, where its upper arm passes when L tilts forward
    data = {
        "bases": {"R2": {"xyz": [2.0, 0.0, 0.0], "rpy_deg": [0, 0, 180]}},
        "obstacles": [{"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75], "frame": "R2"}],
    }
    hc10 = robot_model("hc10").groups[0]
    ws: Workspace = workspace_from_dict(data, "test", ["R1", "R2"])
    world = CollisionWorld((hc10, dataclasses.replace(hc10, name="R2")), ws)
    tilted = [0.0, 0.8, 0.0, 0.0, 0.0, 0.0]
    assert world.contacts([[0.0] * 6, [0.0] * 6]) == []
    assert {c.group for c in world.contacts([[0.0] * 6, tilted])} == {"R2"}
    assert world.contacts([tilted, [0.0] * 6]) == []


def test_lever_arms_grown_by_the_travel_bound_the_motion() -> None:
    world = _world("hc10", [{"name": "far", "sphere": 0.1, "xyz": [5, 5, 5]}])
    world.set_tool(0, Transform((0.0, 0.0, 0.15)))
    body = world.bodies[0]
    assert body is not None
    rng = np.random.default_rng(11)
    for _ in range(40):
        q = rng.uniform(-2.0, 2.0, 6)
        body.place(q)
        levers = np.array(world.lever_arms(0))
        assert np.all(levers <= np.array(world.joint_reach(0)) + 1e-9)
        before = [np.array(p.center) for p in body.all_parts]
        dq = rng.uniform(-0.02, 0.02, 6)
        after = [np.array(p.center) for p in body.place(q + dq)]
        moved = max(float(np.linalg.norm(a - b)) for a, b in zip(after, before, strict=True))
        bound = float(np.dot(np.abs(dq), levers))
        assert moved <= bound + moved * float(np.sum(np.abs(dq)))  # levers grow with travel


def test_turning_s_changes_no_self_distance_of_a_single_arm() -> None:
    world = _world("gp7", [])
    assert world.self_invariant_joints(0) == (0,)
    q = np.array([0.0, 0.8, -0.5, 0.3, 1.0, 0.0])
    d0 = [c.distance_m for c in world.self_distances([q])]
    q[0] = 1.7
    assert [c.distance_m for c in world.self_distances([q])] == pytest.approx(d0, abs=1e-9)
    sda = _world("sda10f", [])
    assert sda.self_invariant_joints(0) == ()  # its base link is the torso beside the arm
