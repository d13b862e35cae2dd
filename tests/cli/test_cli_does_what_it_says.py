"""Issue 20 against a running ``pymotoros sim``: ``run`` checks the start before sending,
``status --watch --count N`` ends, the "stands at" after an E-stop is the settled
position, and ``move --named`` on a robot of several groups says which groups move."""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, estop_a_cli_move, running_sim, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_REFUSED
from pymotoros.client import SyncRobotClient
from pymotoros.client.recording import Direction, read_recording
from pymotoros.models import robot_model
from pymotoros.protocol.constants import Port
from pymotoros.protocol.messages import JointTrajPtFull
from pymotoros.trajectory import Trajectory
from pymotoros.trajectory.files import to_yaml

HC10 = robot_model("hc10")
SDA10F = robot_model("sda10f")
PROCESS_TIMEOUT_S = 60.0
"""Bound on a subprocess's life: a command that never ends fails the test, not the run."""


sim = sim_fixture()


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()])


def _command(sim: Sim, *args: str) -> list[str]:
    return [sys.executable, "-m", "pymotoros", *args, *sim.cli_args()]


def _at_zero(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    result = invoke(sim, "move", "0", "0", "0", "0", "0", "0")
    assert result.exit_code == 0, result.output


# ------------------------------------------------------------------ run: the start


def test_run_away_from_the_start_is_refused_before_anything_is_sent(
    sim: Sim, tmp_path: Path
) -> None:
    _at_zero(sim)
    start = [0.0, 0.0, 0.0, 0.0, 0.01, 0.0]  # joint_5_b 10 mrad away: ~500 pulses
    traj = Trajectory(
        HC10.groups[0].joint_names,
        np.array([0.0, 1.0]),
        np.array([start, [0.1, 0.0, 0.0, 0.0, 0.01, 0.0]]),
        np.zeros((2, 6)),
    )
    path = tmp_path / "away.yaml"
    path.write_text(to_yaml(traj))
    recording = tmp_path / "run.pcapng"
    result = invoke(sim, "run", str(path), "--record", str(recording))
    assert result.exit_code == EXIT_REFUSED, result.output
    line = result.stderr.strip()
    assert "Traceback" not in result.output
    assert len(line.splitlines()) == 1, line
    assert line.startswith("error: point 0 refused: DATA_START_POS (3011)")
    match = re.search(
        r"joint_5_b (\d+) pulses \(\+0\.01000 rad\) from the robot, tolerance 30", line
    )
    assert match is not None, line
    assert int(match.group(1)) > 30
    assert "checked before sending" in line
    assert "What to do: start the trajectory where the robot is" in line
    sent = [
        m
        for conn in read_recording(recording).on(Port.MOTION)
        for m in conn.messages
        if m.direction is Direction.TO_SERVER and isinstance(m.message, JointTrajPtFull)
    ]
    assert sent == []  # nothing streamed


# ------------------------------------------------------------------ status --watch --count


@pytest.mark.parametrize("mode", [[], ["--json"], ["--live"], ["--no-live"]])
def test_watch_count_ends_while_the_robot_stands_still(sim: Sim, mode: list[str]) -> None:
    _at_zero(sim)
    done = subprocess.run(  # noqa: S603 - our own CLI; stdout is a pipe, not a terminal
        _command(sim, "status", "--watch", "--count", "3", "--rate", "20", *mode),
        capture_output=True,
        text=True,
        timeout=PROCESS_TIMEOUT_S,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    if mode == ["--json"]:
        assert len(done.stdout.strip().splitlines()) == 3
    else:
        assert "motion possible" in done.stdout


# ------------------------------------------------------------------ E-stop: settled position


def test_estop_stands_at_is_where_the_robot_came_to_rest(sim: Sim) -> None:
    _at_zero(sim)
    moved = estop_a_cli_move(sim, moving_beyond=0.5, timeout_s=PROCESS_TIMEOUT_S)
    stderr, rest = moved.stderr, moved.rest
    assert moved.returncode == EXIT_REFUSED, stderr
    assert stderr.count("stands at [") == 1, stderr  # said once (the library's stop)
    match = re.search(r"stands at \[([^\]]+)\] rad", stderr)
    assert match is not None, stderr
    told = [float(v) for v in match.group(1).split(",")]
    assert told == pytest.approx(list(rest), abs=2e-4)  # 4 decimals, a settled robot


# ------------------------------------------------------------------ multi-group named poses


@pytest.fixture(scope="module")
def sda() -> Iterator[Sim]:
    with running_sim("--controller", "fs100", "--robot", "sda10f") as s:
        yield s


def _sda(sda: Sim, *args: str) -> Result:
    return invoke(sda, *args, "--controller", "fs100", "--robot", "sda10f")


def _away(sda: Sim) -> None:
    assert _sda(sda, "enable").exit_code == 0
    values = ["0.2"] * 7 + ["-0.2"] * 7 + ["0.1", "0.1"]
    group = ["--group", "R1", "--group", "R2", "--group", "B1", "--group", "B2"]
    result = _sda(sda, "move", *values, *group)
    assert result.exit_code == 0, result.output


def test_named_home_moves_every_group_and_says_which(sda: Sim) -> None:
    _away(sda)
    result = _sda(sda, "move", "--named", "home", "--json")
    assert result.exit_code == 0, result.output
    assert "home: moving R1, R2, B1, B2" in result.stderr
    with SyncRobotClient(controller="fs100", robot="sda10f", **sda.client_options()) as client:
        client.wait_for_state()
        for group in range(4):
            assert client.state.positions(group) == pytest.approx(
                [0.0] * SDA10F.groups[group].num_axes, abs=1e-3
            )


def test_named_home_with_group_moves_only_that_group(sda: Sim) -> None:
    _away(sda)
    result = _sda(sda, "move", "--named", "home", "--group", "R2", "--json")
    assert result.exit_code == 0, result.output
    assert "home: moving R2 (as given with --group)" in result.stderr
    with SyncRobotClient(controller="fs100", robot="sda10f", **sda.client_options()) as client:
        client.wait_for_state()
        assert client.state.positions(1) == pytest.approx([0.0] * 7, abs=1e-3)
        assert client.state.positions(0) == pytest.approx([0.2] * 7, abs=1e-3)  # R1 stayed
