"""Cartesian moves on the twin: straight, on target, within the limits; clear refusals."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.client.cartesian import plan_linear_move, relative_target
from pymotoros.client.planning import JointLimits, PlanningError
from pymotoros.kinematics import chain_for, pose_to_matrix
from pymotoros.models import robot_model
from pymotoros.testing import Twin, twin
from says import assert_says

START = (0.0, 0.5, 1.9, 0.0, 0.9, 0.0)
"""An HC10 pose with the tool well inside the workspace, away from singularities."""
END_TOLERANCE_M = 1e-4  # 0.1 mm (issue 10)
LINE_TOLERANCE_M = 5e-4  # 0.5 mm
TCP_SPEED_MM_S = 200.0
SPEED_SLACK_MM_S = 2.0  # whole-pulse increments per tick: about 1% of 200 mm/s


def _distance_to_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / max(np.dot(ab, ab), 1e-18), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * ab)))


class _LineWatch:
    """At each progress report: distance of the command and feedback TCP to the line, and
    the command TCP speed, from the twin's controller."""

    def __init__(self, tw: Twin, a: np.ndarray, b: np.ndarray) -> None:
        self.tw, self.a, self.b = tw, a, b
        self.chain = chain_for("hc10")
        self.deviations: list[float] = []
        self.speeds: list[float] = []

    def __call__(self, _: object) -> None:
        snap = self.tw.controller.snapshot().groups[0]
        assert snap.tcp is not None
        for q in (snap.command_rad, snap.feedback_rad):
            p = self.chain.fk(list(q))[:3, 3]
            self.deviations.append(_distance_to_segment(p, self.a, self.b))
        self.speeds.append(snap.tcp.command_speed_mm_s)


async def _linear_move_property(offset: tuple[float, float, float]) -> None:
    async with twin(robot="hc10") as (client, tw):
        await client.enable()
        await client.move_joints(START)
        start_pose = np.array(client.tcp_pose())
        goal = (*(start_pose[:3] + np.array(offset)), *start_pose[3:])
        watch = _LineWatch(tw, start_pose[:3], np.array(goal[:3]))
        result = await client.move_linear(goal, tcp_speed_mm_s=TCP_SPEED_MM_S, on_progress=watch)
        deviations, speeds = watch.deviations, watch.speeds
        end = np.array(client.tcp_pose())
        assert np.linalg.norm(end[:3] - np.array(goal[:3])) < END_TOLERANCE_M
        assert len(deviations) > 10
        assert max(deviations) < LINE_TOLERANCE_M
        assert max(speeds) <= TCP_SPEED_MM_S + SPEED_SLACK_MM_S
        limits = client.limits()
        for pt in result.trajectory.points:
            for v, vmax in zip(pt.velocities, limits.max_velocity, strict=True):
                assert abs(v) <= vmax
            for q, lo, hi in zip(pt.positions, limits.lower, limits.upper, strict=True):
                assert lo <= q <= hi


_OFFSET = st.floats(-0.12, 0.12, allow_nan=False)


@settings(max_examples=25, deadline=None, derandomize=True)  # bounded; the same lines in CI
@given(
    offset=st.tuples(_OFFSET, _OFFSET, _OFFSET).filter(
        lambda o: math.dist(o, (0.0, 0.0, 0.0)) > 0.01  # a line, not a point
    )
)
def test_linear_moves_stay_on_the_line_and_end_on_target(
    offset: tuple[float, float, float],
) -> None:
    """Property: any straight line of up to 12 cm per axis from START, on the twin, ends
    within 0.1 mm, leaves the line by less than 0.5 mm and exceeds no limit."""
    asyncio.run(_linear_move_property(offset))


async def test_relative_move_in_the_tool_frame() -> None:
    async with twin(robot="hc10") as (client, _):
        await client.enable()
        await client.move_joints(START)
        before = pose_to_matrix(client.tcp_pose())
        await client.move_relative(dz=-0.05, frame="tool")
        after = pose_to_matrix(client.tcp_pose())
        # 5 cm back along the tool's own z axis, orientation unchanged.
        expected = before[:3, 3] - 0.05 * before[:3, 2]
        assert np.linalg.norm(after[:3, 3] - expected) < END_TOLERANCE_M
        np.testing.assert_allclose(after[:3, :3], before[:3, :3], atol=1e-4)
        await client.move_relative(dx=0.03, drz=0.2, frame="base")
        moved = pose_to_matrix(client.tcp_pose())
        assert moved[0, 3] - after[0, 3] == pytest.approx(0.03, abs=END_TOLERANCE_M)


def test_relative_target_frames() -> None:
    current = pose_to_matrix((0.5, 0.0, 0.3, math.pi, 0.0, 0.0))  # tool pointing down
    down = relative_target(current, (0, 0, 0.1, 0, 0, 0), "tool")
    assert down[:3, 3] == pytest.approx([0.5, 0.0, 0.2])
    up = relative_target(current, (0, 0, 0.1, 0, 0, 0), "base")
    assert up[:3, 3] == pytest.approx([0.5, 0.0, 0.4])
    with pytest.raises(PlanningError, match="'base' or 'tool'"):
        relative_target(current, (0,) * 6, "world")  # type: ignore[arg-type]


def _limits() -> JointLimits:
    return JointLimits.from_group(robot_model("hc10").groups[0])


def test_unreachable_line_is_refused_with_where() -> None:
    chain = chain_for("hc10")
    start_pose = chain.pose(START)
    goal = (start_pose[0] + 2.0, *start_pose[1:])
    with pytest.raises(PlanningError, match=r"leaves the robot's reach at \d+% of the way") as info:
        plan_linear_move(chain, START, goal, _limits())
    message = str(info.value)
    assert "joint_3_u at" in message  # the stretched elbow, with its value
    assert "move_pose" in message  # and what to do


@pytest.mark.parametrize("delta", [(0.0, 0.0, -0.05), (0.45, -0.06, 0.13)])
def test_a_line_from_the_boot_pose_names_the_singularity_and_the_remedy(
    delta: tuple[float, float, float],
) -> None:
    """Issue 20: from the HC10's all-zero boot pose the README's lines were refused with
    "leaves the robot's reach at 2% of the way", naming no joint and no remedy."""
    chain = chain_for("hc10")
    zero = (0.0,) * 6
    pose = chain.pose(zero)
    goal = (pose[0] + delta[0], pose[1] + delta[1], pose[2] + delta[2], *pose[3:])
    with pytest.raises(PlanningError) as info:
        plan_linear_move(chain, zero, goal, _limits())
    assert_says(
        str(info.value),
        "singularity",
        "joint_5_b",
        "joint_4_r",
        "move_joints([0, 0, 1.047, 0, -1.047, 0])",
        "--pose without --linear",
    )
    ready = chain.pose((0.0, 0.0, 1.047, 0.0, -1.047, 0.0))
    plan_linear_move(
        chain,
        (0.0, 0.0, 1.047, 0.0, -1.047, 0.0),
        (*ready[:2], ready[2] - 0.05, *ready[3:]),
        _limits(),
    )


def test_joint_limit_is_refused_with_joint_and_amount() -> None:
    # Tool down, rotating about base z turns T (±180°) past its limit at some point.
    chain = chain_for("hc10")
    start = (0.0, 0.5, 1.9, 0.0, 0.9, 3.0)
    pose = chain.pose(start)
    goal = (*pose[:5], pose[5] - 0.5)
    with pytest.raises(PlanningError, match=r"joint_6_t would reach .* beyond its (upper|lower)"):
        plan_linear_move(chain, start, goal, _limits())


def test_line_through_a_singularity_is_refused() -> None:
    # GP7 wrist singularity: at B = 0 the R and T axes line up (robot-models.md §1.3). The
    # line between B = +0.2 and B = -0.2 with R at 1 rad needs T to spin through it.
    chain = chain_for("gp7")
    limits = JointLimits.from_group(robot_model("gp7").groups[0])
    start = (0.0, 0.3, 0.2, 1.0, 0.2, 0.0)
    goal = chain.pose((0.0, 0.3, 0.2, 1.0, -0.2, 0.0))
    with pytest.raises(PlanningError, match=r"singularity at \d+% .* joint_\d_\w would turn"):
        plan_linear_move(chain, start, goal, limits)


def test_tcp_speed_is_checked() -> None:
    with pytest.raises(PlanningError, match="tcp_speed_mm_s"):
        plan_linear_move(
            chain_for("hc10"), START, chain_for("hc10").pose(START), _limits(), tcp_speed_mm_s=0.0
        )
