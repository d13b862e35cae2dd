"""Kinematics on Pinocchio, checked against an independent numpy chain and by hand."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

from pymotoros.errors import KinematicsError
from pymotoros.kinematics import chain_for, matrix_to_pose, pose_to_matrix, urdf_for
from pymotoros.models.robots import ROBOTS, GroupModel, Transform

CASES = [(name, i) for name, robot in ROBOTS.items() for i in range(len(robot.groups))]
SAMPLES = 12
ROUND_TRIP_TOLERANCE = 1e-6  # m and rad, the acceptance


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' formula, written out: the independent rotation of the reference chain."""
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    x_, y_, z_ = np.eye(3)
    return _rot(z_, y) @ _rot(y_, p) @ _rot(x_, r)


def _tf(frame: Transform) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = _rpy(*frame.rpy)
    m[:3, 3] = frame.xyz
    return m


def _reference_fk(group: GroupModel, q: np.ndarray, tool: Transform | None = None) -> np.ndarray:
    """tcp in base_link by plain matrix products over the model data (no Pinocchio)."""
    m = _tf(group.mount)
    for axis, angle in zip(group.axes, q, strict=True):
        assert axis.geometry is not None
        m = m @ _tf(axis.geometry.origin)
        joint = np.eye(4)
        joint[:3, :3] = _rot(np.array(axis.geometry.axis), float(angle))
        m = m @ joint
    return m @ _tf(group.tool0 or Transform()) @ _tf(tool or Transform())


@pytest.mark.parametrize(("robot", "index"), CASES)
def test_fk_matches_an_independent_matrix_chain(robot: str, index: int) -> None:
    group = ROBOTS[robot].groups[index]
    tool = Transform((0.01, -0.02, 0.15), (0.1, -0.2, 0.3))
    chain = chain_for(group, tool)
    rng = np.random.default_rng(index + len(robot))
    for _ in range(SAMPLES):
        q = rng.uniform(chain.lower, chain.upper)
        expected = _reference_fk(group, q, tool)
        np.testing.assert_allclose(chain.fk(q, "tcp", "base_link"), expected, atol=1e-12)
        in_base = expected.copy()
        in_base[2, 3] -= group.base_height
        np.testing.assert_allclose(chain.fk(q, "tcp", "base"), in_base, atol=1e-12)


def test_hc10_zero_pose_by_hand() -> None:
    # robot-models.md §1.2: S at 0.275, U 0.700 up, B 0.500 down, B offset 0.162 sideways,
    # tool0 0.130 below the T axis and rolled by π: the folded arm's flange points down.
    chain = chain_for("hc10")
    x, y, z, rx, ry, rz = chain.pose([0.0] * 6, "tool0", "base_link")
    assert (x, y, z) == pytest.approx((0.0, 0.162, 0.275 + 0.700 - 0.500 - 0.130), abs=1e-12)
    assert abs(rx) == pytest.approx(math.pi)
    assert (ry, rz) == pytest.approx((0.0, 0.0), abs=1e-12)
    # In the base frame the S-axis height is gone.
    assert chain.pose([0.0] * 6, "tool0")[2] == pytest.approx(0.700 - 0.500 - 0.130)


def test_gp7_stretched_pose_by_hand() -> None:
    # robot-models.md §1.3, all joints 0: x = 0.040 + 0.440 + 0.080, z = 0.330 + 0.445 + 0.040,
    # tool0 z pointing along +x of base_link.
    chain = chain_for("gp7")
    m = chain.fk([0.0] * 6, "tool0", "base_link")
    np.testing.assert_allclose(m[:3, 3], [0.560, 0.0, 0.815], atol=1e-12)
    np.testing.assert_allclose(m[:3, 2], [1.0, 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(("robot", "index"), CASES)
def test_jacobian_matches_finite_differences(robot: str, index: int) -> None:
    group = ROBOTS[robot].groups[index]
    chain = chain_for(group)
    q = np.random.default_rng(3).uniform(chain.lower, chain.upper) * 0.9
    j = chain.jacobian(q)
    h = 1e-7
    base = _reference_fk(group, q)
    for i in range(chain.num_joints):
        dq = q.copy()
        dq[i] += h
        moved = _reference_fk(group, dq)
        np.testing.assert_allclose(j[:3, i], (moved[:3, 3] - base[:3, 3]) / h, atol=1e-5)
        omega = (moved[:3, :3] @ base[:3, :3].T - np.eye(3)) / h
        np.testing.assert_allclose(j[3:, i], [omega[2, 1], omega[0, 2], omega[1, 0]], atol=1e-5)


@pytest.mark.parametrize(("robot", "index"), CASES)
def test_ik_round_trip_within_limits(robot: str, index: int) -> None:
    chain = chain_for(ROBOTS[robot].groups[index])
    rng = np.random.default_rng(11 + index)
    for _ in range(SAMPLES):
        q = rng.uniform(chain.lower, chain.upper)
        target = chain.fk(q)
        seed = np.clip(q + rng.normal(0.0, 0.3, q.shape), chain.lower, chain.upper)
        result = chain.ik(target, seed)
        assert np.all(result.q >= chain.lower)
        assert np.all(result.q <= chain.upper)
        reached = chain.fk(result.q)
        assert np.abs(reached[:3, 3] - target[:3, 3]).max() < ROUND_TRIP_TOLERANCE
        rot_err = pin.log3(reached[:3, :3] @ target[:3, :3].T)
        assert np.linalg.norm(rot_err) < ROUND_TRIP_TOLERANCE
        # The independent chain agrees on where the solution puts the TCP.
        ref = _reference_fk(chain.group, result.q)
        ref[2, 3] -= chain.base_height
        np.testing.assert_allclose(ref, target, atol=ROUND_TRIP_TOLERANCE)


def test_ik_from_a_solution_returns_that_solution() -> None:
    chain = chain_for("gp7")
    q = np.array([0.3, 0.4, -0.2, 0.5, -0.6, 0.7])
    np.testing.assert_allclose(chain.ik(chain.pose(q), q).q, q, atol=1e-9)


def test_ik_picks_the_branch_of_the_seed() -> None:
    # Elbow up and elbow down reach the same pose; each seed gets its own branch.
    chain = chain_for("gp7")
    a = np.array([0.2, 0.3, 0.4, 0.1, -0.8, 0.2])
    pose = chain.pose(a)
    solved = chain.ik(pose, a + 0.05).q
    np.testing.assert_allclose(solved, a, atol=1e-7)


def test_ik_refuses_an_unreachable_pose_with_the_distance() -> None:
    chain = chain_for("hc10")
    with pytest.raises(KinematicsError, match=r"no joint values.*mm"):
        chain.ik((3.0, 0.0, 0.5, 0.0, 0.0, 0.0), [0.0] * 6, restarts=2)


def test_pose_matrix_round_trip_uses_rz_ry_rx() -> None:
    pose = (0.1, -0.2, 0.3, 0.4, -0.5, 0.6)
    m = pose_to_matrix(pose)
    np.testing.assert_allclose(m[:3, :3], _rpy(0.4, -0.5, 0.6), atol=1e-15)
    assert matrix_to_pose(m) == pytest.approx(pose)
    with pytest.raises(KinematicsError, match="6 values"):
        pose_to_matrix((1.0, 2.0))


def test_wrong_number_of_joints_is_refused() -> None:
    with pytest.raises(KinematicsError, match="6 joints, got 5"):
        chain_for("hc10").fk([0.0] * 5)


def test_tcp_speed_of_a_step_matches_the_jacobian() -> None:
    chain = chain_for("hc10", Transform((0.0, 0.0, 0.2)))
    q = np.array([0.1, 0.5, 1.8, 0.2, 0.4, 0.0])
    qd = np.array([0.3, -0.2, 0.1, 0.5, 0.4, 0.2])
    dt = 0.004
    step = chain.tcp_speed(q, qd * dt, dt)
    assert step == pytest.approx(chain.tcp_velocity(q, qd), rel=1e-3)
    assert step > 0


def test_joint_frames_are_json_and_end_at_the_tcp() -> None:
    chain = chain_for("gp12")
    q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    frames = chain.joint_frames(q)
    json.dumps(frames)
    assert [f["name"] for f in frames][-3:] == ["flange", "tool0", "tcp"]
    assert len(frames) == 9
    np.testing.assert_allclose(
        frames[-1]["xyz"], chain.fk(q, "tcp", "base_link")[:3, 3], atol=1e-12
    )


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_urdf_loads_in_a_urdf_library_and_agrees(robot: str) -> None:
    text = urdf_for(ROBOTS[robot])
    model = pin.buildModelFromXML(text)  # urdfdom's parser, as RViz and MoveIt use
    data = model.createData()
    rng = np.random.default_rng(5)
    several = len(ROBOTS[robot].groups) > 1
    for index, group in enumerate(ROBOTS[robot].groups):
        chain = chain_for(group)
        q_group = rng.uniform(chain.lower, chain.upper)
        q = pin.neutral(model)
        for name, value in zip(group.joint_names, q_group, strict=True):
            q[model.joints[model.getJointId(name)].idx_q] = value
        pin.framesForwardKinematics(model, data, q)
        tool0 = f"{group.name.lower()}_tool0" if several else "tool0"
        placement = data.oMf[model.getFrameId(tool0)]
        np.testing.assert_allclose(
            placement.homogeneous, chain.fk(q_group, "tool0", "base_link"), atol=1e-9
        )
        assert index < len(ROBOTS[robot].groups)
        if group.base_height:
            base = data.oMf[model.getFrameId("base")]
            assert base.translation[2] == pytest.approx(group.base_height)


def test_each_chain_owns_its_workspace() -> None:
    """Issue 19: one ``lru_cache``d chain (and its mutable Pinocchio data) was shared by
    the controller and the client. Now each call gives a chain of its own; only the
    read-only model behind is built once."""
    a, b = chain_for("hc10"), chain_for("hc10")
    assert a is not b
    assert a._data is not b._data
    assert a.model is b.model
    q1, q2 = [0.1, 0.5, 1.9, 0.0, 0.9, 0.0], [-0.4, 0.2, 1.2, 0.3, -0.8, 0.5]
    expected = (a.pose(q1), b.pose(q2))
    a.fk(q1)
    b.fk(q2)  # b's work leaves a's workspace alone
    x, y, z = expected[0][:3]
    tcp = a._data.oMf[a.model.getFrameId("tcp")].translation.tolist()
    assert tcp == pytest.approx([x, y, z + a.base_height])
    assert not hasattr(a, "singular_value")
