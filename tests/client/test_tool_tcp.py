"""The tool is the TCP: every Cartesian operation uses the tool in force, never a guess.

On the in-memory twin with the example cell whose tool 1 is a 150 mm gripper: a pose
move places the gripper's TCP (as the twin computes it with its own tool data) within
1 mm of the request; a client that cannot know the tool refuses before moving.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import AsyncIterator
from pathlib import Path

import pytest

from pymotoros.client import PlanningError, RobotClient
from pymotoros.client.streaming import FollowingSample
from pymotoros.client.tools import ToolTable, ToolUnknownError
from pymotoros.controller.cell import load_cell
from pymotoros.models import robot_model
from pymotoros.models.cell import load_cell_models
from pymotoros.testing import Twin, twin

CELL = Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_register_outputs.toml"
REQUEST = (0.6, 0.1, 0.3, math.pi, 0.0, 0.0)
MM = 1e-3


@contextlib.asynccontextmanager
async def cell_twin(**options: object) -> AsyncIterator[tuple[RobotClient, Twin]]:
    """The example cell's twin and a client that read the same cell file."""
    async with Twin(load_cell(CELL)) as tw, tw.client(cell=CELL, **options) as client:
        await client.wait_for_state()
        yield client, tw


def _twin_tcp(tw: Twin) -> tuple[float, ...]:
    """The TCP as the twin computes it, with the tool the controller has selected."""
    tcp = tw.controller.snapshot().groups[0].tcp
    assert tcp is not None
    return tcp.feedback


def test_the_cell_file_gives_the_client_its_tools() -> None:
    tools = load_cell_models(CELL).tools
    assert [(t.number, t.name, t.tcp.xyz) for t in tools[0]] == [(1, "gripper", (0, 0, 0.15))]
    client = RobotClient(cell=CELL)
    assert client.tools.describe(0, 1) == "tool 1 (gripper, TCP x 0.0 y 0.0 z 150.0 mm on tool0)"
    assert client.tools.describe(0, 0) == "tool 0 (TCP = tool0, no offset)"


@pytest.mark.parametrize("linear", [False, True])
async def test_a_pose_move_places_the_gripper_tcp_within_1_mm(linear: bool) -> None:
    async with cell_twin() as (client, tw):
        await client.enable()
        await client.select_tool(1)
        if linear:  # a line from the boot pose would cross the wrist singularity
            await client.move_pose((0.55, 0.1, 0.35, math.pi, 0.0, 0.0))
        await client.move_cartesian(REQUEST, linear=linear)
        assert _twin_tcp(tw) == pytest.approx(REQUEST, abs=MM)
        assert client.tcp_pose() == pytest.approx(REQUEST, abs=MM)
        tool0 = client.tcp_pose(frame="tool0")
        assert tool0[2] == pytest.approx(REQUEST[2] + 0.15, abs=MM)  # the flange stays above


async def test_the_tool_named_at_construction_is_the_tcp() -> None:
    """``RobotClient(tool=1)`` (what ``--tool 1`` does for status): known, no SELECT_TOOL."""
    async with cell_twin(tool=1) as (client, tw):
        await client.enable()
        tw.controller.select_tool(0, 1)  # selected by someone else (the pendant, a job)
        await client.move_pose(REQUEST)
        assert _twin_tcp(tw) == pytest.approx(REQUEST, abs=MM)


async def test_an_unknown_tool_is_refused_before_anything_moves() -> None:
    async with cell_twin() as (client, tw):
        await client.enable()
        before = client.state.positions(0)
        for move in (client.move_pose, client.move_linear):
            with pytest.raises(ToolUnknownError, match=r"--tool N.*") as info:
                await move(REQUEST)
            assert "tool 1 (gripper, TCP x 0.0 y 0.0 z 150.0 mm on tool0)" in str(info.value)
            assert "\n" not in str(info.value)
        with pytest.raises(ToolUnknownError):
            await client.move_relative(dz=-0.01)
        with pytest.raises(ToolUnknownError):
            client.tcp_pose()
        assert isinstance(ToolUnknownError("x"), PlanningError)  # exit code 2 in the CLI
        assert client.tcp_pose(frame="tool0")  # tool0 does not depend on the tool
        assert client.tcp_pose(tool=1)  # nor does a pose computed for a named tool
        await tw.sleep(0.5)
        assert client.state.positions(0) == before


def test_without_tool_data_the_tcp_is_tool0() -> None:
    table = ToolTable(robot_model("hc10"))
    assert table.in_force(0) == 0
    table.define(2, (0.0, 0.0, 0.1), name="probe")
    with pytest.raises(ToolUnknownError, match="tool 2 \\(probe"):
        table.in_force(0)
    table.use(2)
    assert table.in_force(0) == 2
    assert table.chain(0).tool.xyz == (0.0, 0.0, 0.1)
    with pytest.raises(ValueError, match=r"0\.\.63"):
        table.use(64)


async def test_move_relative_as_a_joint_move_reports_progress() -> None:
    """Issue 19: ``move_relative(linear=False)`` dropped ``on_progress``."""
    samples: list[FollowingSample] = []
    async with twin(robot="hc10") as (client, _):
        await client.enable()
        await client.move_joints((0.0, 0.5, 1.9, 0.0, 0.9, 0.0))
        before = client.tcp_pose()
        await client.move_relative(dz=-0.02, linear=False, on_progress=samples.append)
        assert client.tcp_pose()[2] == pytest.approx(before[2] - 0.02, abs=1e-4)
    assert samples, "no progress reported"


async def test_the_client_and_the_twin_never_share_a_kinematics_workspace() -> None:
    async with cell_twin(tool=1) as (client, tw):
        mine = client.tools.chain(0)
        theirs = tw.controller._tcp.chain(0, 1)  # the twin's own chain
        assert theirs is not None
        assert mine is not theirs
        assert mine._data is not theirs._data
        assert mine.model is theirs.model  # the read-only model is built once


def test_the_blocking_tcp_pose_waits_for_the_first_state() -> None:
    """README: ``tcp_pose()`` right after connecting answered "no joint feedback for
    group 0 yet" (the state port had sent nothing yet)."""
    from client_sim import running_sim

    from pymotoros.client import SyncRobotClient

    with running_sim() as sim, SyncRobotClient(robot="hc10", **sim.client_options()) as robot:
        # (usually nothing has arrived yet here: the state port sends every 25 ms)
        pose = robot.tcp_pose()
        assert pose[1] == pytest.approx(0.162, abs=1e-3)  # the boot pose, tool0


def test_the_readme_example_runs_as_written() -> None:
    """README "Where the tool is": the Python block and the shell block, as written, against
    a sim (only the ports are pointed at it)."""
    import re

    from click.testing import CliRunner
    from client_sim import running_sim

    from pymotoros.cli.main import cli

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index("### Where the tool is") :]
    python = re.search(r"```python\n(.*?)```", section, re.S)
    shell = re.search(r"```sh\n(.*?)```", section, re.S)
    assert python is not None
    assert shell is not None
    with running_sim() as sim:
        ports = ", ".join(f"{k}={v}" for k, v in sim.client_options().items())
        connect = 'SyncRobotClient("127.0.0.1", '
        code = python.group(1).replace(connect, f"SyncRobotClient({ports}, ")
        assert ports in code
        exec(compile(code, "README.md", "exec"), {})  # noqa: S102 - our own README
        for line in shell.group(1).splitlines():
            args = line.partition("#")[0].split()
            if not args or args[1] not in ("move", "status"):
                continue
            result = CliRunner().invoke(cli, [*args[1:], *sim.cli_args()])
            assert result.exit_code == 0, f"{line}: {result.output}"


def test_cell_tools_per_group_with_the_same_rules_as_the_sim() -> None:
    from pymotoros.errors import ConfigError
    from pymotoros.models.cell import cell_models_from_dict

    cell = cell_models_from_dict(
        {
            "controller": {"model": "fs100"},
            "groups": [{"robot": "sda10f", "tools": [{"number": 2, "tcp_m": [0, 0, 0.1]}]}],
            "tools": [{"number": 2, "name": "cell-wide"}, {"number": 3, "name": "probe"}],
        }
    )
    numbers = [[(t.number, t.name, t.tcp.xyz[2]) for t in group] for group in cell.tools]
    arm = [(2, "", 0.1), (3, "probe", 0.0)]  # the entry's own tool 2 wins over the cell's
    assert numbers == [arm, arm, [], []]  # R1, R2 take tools; the bases B1, B2 do not
    with pytest.raises(ConfigError, match=r"tools\[0\]\.tcp_m: must be three numbers"):
        cell_models_from_dict({"tools": [{"number": 2, "tcp_m": [0, 0]}]})
    with pytest.raises(ConfigError, match=r"tools\[0\]\.number: must lie in 0\.\.63"):
        cell_models_from_dict({"tools": [{"number": 64}]})
    with pytest.raises(ConfigError, match="tool 1 appears twice"):
        cell_models_from_dict({"tools": [{"number": 1}, {"number": 1}]})
