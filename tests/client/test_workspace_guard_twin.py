"""Every move of the client is checked against the obstacles of its cell file (issue 29
item 3), on the in-memory twin of ``examples/cells/hc10_table_fixture.toml``.

Cartesian moves (``move_pose``, ``move_linear``, ``move_relative``) are refused before
anything is sent, as joint moves are, naming the time, link, obstacle and depth;
``force=True`` sends them anyway (and the twin's PFL stops the arm at the fixture, the
error naming the contact); a robot that touches an obstacle may back out of it and
nothing else; ``avoid=True`` works for a pose goal and leaves a contact first.
"""

from __future__ import annotations

import asyncio
import math
import re
import tomllib
from pathlib import Path

import pytest
from cell_twin import twin_of_cell
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from pymotoros import PathBlockedError
from pymotoros.client import NotReadyError, RobotClient
from pymotoros.controller.cell import cell_from_dict, load_cell
from pymotoros.models.cell import cell_models_from_dict, load_cell_models
from pymotoros.testing import Twin

CELL = Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_table_fixture.toml"
INTO_THE_FIXTURE = (0.70, 0.0, -0.10, math.pi, 0.0, 0.0)
"""The issue's pose: the gripper 75 mm into the fixture's top (base coordinates)."""
ABOVE_THE_FIXTURE = (0.70, 0.0, 0.10, math.pi, 0.0, 0.0)
"""125 mm above the fixture's top, tool pointing down: clear of everything."""
PFL_LATCH_S = 0.6
"""The twin's PFL stop holds 500 ms before START_TRAJ_MODE clears it."""


async def _ready(the_twin: Twin) -> RobotClient:
    client = the_twin.client(cell=load_cell_models(CELL), tool=0)
    await client.connect()
    await client.wait_for_state()
    await client.enable()
    return client


def _contacts(the_twin: Twin) -> list[object]:
    return list(the_twin.controller.snapshot().workspace.contacts)


async def test_move_pose_into_the_fixture_is_refused_before_anything_moves() -> None:
    async with Twin(load_cell(CELL)) as the_twin:
        client = await _ready(the_twin)
        before = await client.current_positions()
        with pytest.raises(PathBlockedError) as info:
            await client.move_pose(INTO_THE_FIXTURE)
        text = str(info.value)
        assert text.startswith("the planned move would hit: collision at ")
        assert "s: R1 tool touches obstacle 'fixture' (" in text
        assert "mm deep, until " in text
        assert "nothing was sent" in text
        assert "force=True" in text
        assert await client.current_positions() == pytest.approx(before, abs=1e-9)
        assert the_twin.controller.snapshot().pfl == "idle"
        await client.close()


@pytest.mark.parametrize("how", ["move_linear", "move_relative", "move_pose"])
async def test_every_cartesian_move_is_guarded(how: str) -> None:
    async with Twin(load_cell(CELL)) as the_twin:
        client = await _ready(the_twin)
        await client.move_pose(ABOVE_THE_FIXTURE)  # clear: the guard lets it go
        before = await client.current_positions()
        down = (
            client.move_relative(dz=-0.2)
            if how == "move_relative"
            else getattr(client, how)(INTO_THE_FIXTURE)
        )
        with pytest.raises(PathBlockedError, match="R1 tool touches obstacle 'fixture'"):
            await down
        assert await client.current_positions() == pytest.approx(before, abs=1e-9)
        assert _contacts(the_twin) == []
        await client.close()


def _gripper_is_tool_1() -> dict[str, object]:
    """The fixture cell with the gripper as tool 1: tool 0 (in force) is the bare flange."""
    data = tomllib.loads(CELL.read_text())
    data["tools"] = [dict(data["tools"][0], number=1)]
    return data


@pytest.mark.parametrize("how", ["move_linear", "move_relative", "move_pose"])
async def test_the_guard_mounts_the_moves_own_tool(how: str) -> None:
    """A move planned with ``tool=1``'s TCP is checked with tool 1's shape on the flange,
    not with the tool in force (once refused nothing: tool 0 has no shape)."""
    data = _gripper_is_tool_1()
    async with Twin(cell_from_dict(data)) as the_twin:
        client = the_twin.client(cell=cell_models_from_dict(data), tool=0)
        await client.connect()
        await client.wait_for_state()
        await client.enable()
        await client.move_pose(ABOVE_THE_FIXTURE, tool=1)
        before = await client.current_positions()
        down = (
            client.move_relative(dz=-0.2, tool=1)
            if how == "move_relative"
            else getattr(client, how)(INTO_THE_FIXTURE, tool=1)
        )
        with pytest.raises(PathBlockedError, match="R1 tool touches obstacle 'fixture'"):
            await down
        assert await client.current_positions() == pytest.approx(before, abs=1e-9)
        assert the_twin.controller.snapshot().pfl == "idle"
        await client.close()


async def test_forced_move_stops_at_the_fixture_and_the_error_names_the_contact() -> None:
    async with Twin(load_cell(CELL)) as the_twin:
        client = await _ready(the_twin)
        with pytest.raises(NotReadyError) as info:
            await client.move_pose(INTO_THE_FIXTURE, force=True)
        text = str(info.value)
        assert "PFL 5011 (power and force limiting): where it stopped, R1 tool touches " in text
        assert "obstacle 'fixture' (" in text
        assert "mm deep)" in text
        # it stands in the fixture: going deeper is refused, with the way out
        here = await client.current_positions()
        with pytest.raises(PathBlockedError) as deeper:
            await client.move_relative(dz=-0.01)
        words = str(deeper.value)
        assert words.startswith("the robot starts touching obstacle 'fixture' (R1 tool)")
        assert "this move does not take it away" in words
        assert "A move along which the clearance only grows is allowed" in words
        assert "--relative dx=-0.020 --tool 0` with this cell's --config" in words  # guarded
        assert "--force" in words
        assert await client.current_positions() == pytest.approx(here, abs=1e-9)
        # backing out (the hint) is allowed, and the twin lets the arm leave
        await the_twin.sleep(PFL_LATCH_S)
        await client.enable()
        result = await client.move_relative(dx=-0.02)
        assert result.final_positions != pytest.approx(here, abs=1e-3)
        assert the_twin.controller.snapshot().pfl == "idle"
        await client.close()


async def test_avoid_leaves_a_contact_then_goes_around() -> None:
    async with Twin(load_cell(CELL)) as the_twin:
        client = await _ready(the_twin)
        with pytest.raises(NotReadyError):
            await client.move_pose(INTO_THE_FIXTURE, force=True)
        await the_twin.sleep(PFL_LATCH_S)
        await client.enable()
        result = await client.move_pose(ABOVE_THE_FIXTURE, avoid=True)
        assert client.tcp_pose()[:3] == pytest.approx(ABOVE_THE_FIXTURE[:3], abs=2e-3)
        assert len(result.trajectory.points) > 2
        assert the_twin.controller.snapshot().pfl == "idle"
        await client.close()


async def test_avoid_refuses_a_pose_goal_in_collision_naming_the_obstacle() -> None:
    async with Twin(load_cell(CELL)) as the_twin:
        client = await _ready(the_twin)
        before = await client.current_positions()
        with pytest.raises(PathBlockedError) as info:
            await client.move_pose(INTO_THE_FIXTURE, avoid=True)
        assert str(info.value) == (
            "the goal is in collision: obstacle 'fixture' (R1 tool touches it)"
        )
        assert await client.current_positions() == pytest.approx(before, abs=1e-9)
        with pytest.raises(Exception, match="a straight line cannot go around them"):
            await client.move_cartesian(ABOVE_THE_FIXTURE, linear=True, avoid=True)
        await client.close()


BALL = {"name": "ball", "sphere": 0.1, "xyz": [0.45, 0.0, 0.75]}
LEFT = [-0.8, 0.6, 0.0, 0.0, 0.0, 0.0]
RIGHT = [0.8, 0.6, 0.0, 0.0, 0.0, 0.0]


async def test_avoid_goes_around_the_ball_to_a_pose() -> None:
    data = {
        "robot": {"model": "hc10"},
        "initial": {"joints": {"R1": LEFT}},
        "workspace": {"obstacles": [BALL]},
    }
    async with twin_of_cell(data) as (client, the_twin):
        goal = client.tools.chain(0).pose(RIGHT, "tcp", "base")
        with pytest.raises(PathBlockedError, match="the planned move would hit"):
            await client.move_pose(goal)  # straight in joint space: not free
        await client.move_pose(goal, avoid=True)
        assert client.tcp_pose()[:3] == pytest.approx(goal[:3], abs=2e-3)
        assert the_twin.controller.snapshot().workspace.contacts == ()


GP7_BOX = {
    "robot": {"model": "gp7"},
    "workspace": {"obstacles": [{"name": "box", "box": [0.2, 0.2, 0.2], "xyz": [0.6, 0.0, 0.3]}]},
}


async def test_a_collision_alarm_names_the_alarm_link_and_obstacle() -> None:
    async with twin_of_cell(GP7_BOX) as (client, _the_twin):
        with pytest.raises(PathBlockedError, match="obstacle 'box'"):
            await client.move_joints([0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
        with pytest.raises(NotReadyError) as info:
            await client.move_joints([0.0, 1.0, 0.0, 0.0, 0.0, 0.0], force=True)
        text = str(info.value)
        assert text.startswith("point ")
        assert "refused: ALARM (5001): an alarm is active." in text
        named = re.search(
            r"; alarm 4315 COLLISION DETECT: where it stopped, R1 (link_\w+) touches obstacle "
            r"'box' \((\d+\.\d) mm deep\)$",
            text,
        )
        assert named is not None, text
        link, depth = named.groups()
        assert 0.0 < float(depth) < 20.0  # stopped within a few ticks' travel
        # standing in the box: the guard says how deep, from the same cell file
        with pytest.raises(PathBlockedError) as deeper:
            await client.move_joints([0.0, 1.2, 0.0, 0.0, 0.0, 0.0])
        assert str(deeper.value).startswith(
            f"the robot starts touching obstacle 'box' (R1 {link}) ({depth} mm deep)"
        )


INSIDE = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0]
"""The elbow inside the ball (as a robot stopped in it stands)."""
OUT = [0.0, 1.2, 0.0, 0.0, 0.0, 0.0]
"""L tilted further forward: the upper arm leaves the ball (18 mm deep at INSIDE, clear
from L = 1.1 rad on); tilting back would pass its middle (148 mm deep at L = 0.8)."""


def _stuck_in_the_ball() -> dict[str, object]:
    return {
        "robot": {"model": "hc10"},
        "initial": {"joints": {"R1": INSIDE}},
        "workspace": {"obstacles": [BALL]},
    }


async def test_a_joint_move_backs_out_of_a_contact_and_nothing_else() -> None:
    data = _stuck_in_the_ball()
    async with twin_of_cell(data) as (client, the_twin):
        with pytest.raises(PathBlockedError) as info:
            await client.move_joints([0.0, 0.4, 0.0, 0.0, 0.0, 0.0])  # through its middle
        text = str(info.value)
        assert text.startswith("the robot starts touching obstacle 'ball' (R1 link_2_l)")
        assert "the overlap grows to " in text
        assert "A move along which the clearance only grows is allowed" in text
        assert await client.current_positions() == pytest.approx(INSIDE, abs=1e-5)
        result = await client.move_joints(OUT)  # out of it all the way: allowed
        assert list(result.final_positions) == pytest.approx(OUT, abs=1e-3)
        assert the_twin.controller.snapshot().pfl == "idle"


async def test_avoid_from_a_start_in_contact_leaves_it_first() -> None:
    data = _stuck_in_the_ball()
    async with twin_of_cell(data) as (client, the_twin):
        result = await client.move_joints(RIGHT, avoid=True)  # was "the start is in collision"
        assert list(result.final_positions) == pytest.approx(RIGHT, abs=1e-3)
        snapshot = the_twin.controller.snapshot()
        assert snapshot.pfl == "idle"
        assert snapshot.workspace.contacts == ()


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    goal=st.tuples(
        st.floats(-0.6, 0.6),
        st.floats(0.2, 1.4),
        st.floats(-0.05, 1.2),
        st.floats(-0.5, 0.5),
        st.floats(-1.5, 0.5),
        st.floats(-0.5, 0.5),
    )
)
def test_the_guard_and_the_twin_agree(goal: tuple[float, ...]) -> None:
    """Any joint move in the fixture cell: refused before anything moves, or run without
    the twin (which checks every tick's commanded position) feeling any contact."""
    asyncio.run(_guarded_move(goal))


async def _guarded_move(goal: tuple[float, ...]) -> None:
    async with Twin(load_cell(CELL)) as the_twin:
        client = await _ready(the_twin)
        felt: list[object] = []
        the_twin.on_tick(lambda: felt.extend(the_twin.controller.workspace_contacts))
        before = await client.current_positions()
        try:
            await client.move_joints(list(goal))
        except PathBlockedError:
            event("refused")
            assert await client.current_positions() == pytest.approx(before, abs=1e-9)
        else:
            event("moved")
            assert await client.current_positions() == pytest.approx(goal, abs=1e-3)
        assert felt == []
        assert the_twin.controller.snapshot().pfl == "idle"
        await client.close()
