"""Issue 14 from the command line: a two-arm cell, stopping, reset/servo, -v, ports file."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_CONNECTION, EXIT_TERMINATED, EXIT_USAGE
from pymotoros.client import SyncRobotClient

ROOT = Path(__file__).resolve().parents[2]
CELL = ROOT / "examples" / "cells" / "two_hc10_dx100.toml"
SIGTERM_WAIT_S = 20.0
"""Bound on how long the moving process may take to stop and exit after SIGTERM."""


@pytest.fixture(scope="module")
def two_arms(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Sim, Path]]:
    ports = tmp_path_factory.mktemp("ports") / "ports.json"
    with running_sim("--config", str(CELL), "--ports-file", str(ports)) as sim:
        yield sim, ports


def invoke(ports: Path, *args: str, env: dict[str, str] | None = None) -> Result:
    """``pymotoros ARGS`` against the two-arm sim found through the ports file (env var)."""
    environment = {"PYMOTOROS_PORTS_FILE": str(ports), "PYMOTOROS_CONFIG": str(CELL)}
    return CliRunner().invoke(cli, list(args), env={**environment, **(env or {})})


def _positions(result: Result) -> list[float]:
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    return [p for g in data["groups"] for p in g["positions"]]


def test_ports_file_has_the_ready_line_ports(two_arms: tuple[Sim, Path]) -> None:
    sim, ports = two_arms
    data = json.loads(ports.read_text())
    top = {k: data[k] for k in ("motion", "state", "io", "http")}
    assert top == {"motion": sim.motion, "state": sim.state, "io": sim.io, "http": sim.http}
    (cell,) = data["cells"]  # and what the cell is: no --config needed to read it
    assert (cell["controller"], cell["robots"]) == ("dx100", ["hc10"])
    assert [g["name"] for g in cell["groups"]] == ["R1", "R2"]


def _ports_only(ports: Path) -> Path:
    """A ports file as written before it carried the cell: the client knows no models."""
    data = json.loads(ports.read_text())
    old = ports.with_name("ports_only.json")
    old.write_text(json.dumps({k: data[k] for k in ("motion", "state", "io", "http")}))
    return old


def test_two_arms_group_by_group_and_together(two_arms: tuple[Sim, Path]) -> None:
    _, ports = two_arms
    assert invoke(ports, "enable").exit_code == 0
    r1 = ["0.1", "0.4", "0.9", "0", "-0.4", "0.2"]
    r2 = ["-0.1", "-0.4", "0.9", "0", "0.4", "-0.2"]
    result = invoke(ports, "move", "--group", "R2", *r2)
    assert result.exit_code == 0, result.output
    result = invoke(ports, "move", "--group", "0", *r1, "--json")
    assert result.exit_code == 0, result.output
    status = _positions(invoke(ports, "status", "--json"))
    assert max(abs(a - float(b)) for a, b in zip(status, r1 + r2, strict=True)) < 1e-3
    both = ["0", "0.5", "1", "0", "-0.5", "0", "0", "-0.5", "1", "0", "0.5", "0"]
    result = invoke(ports, "move", "--group", "R1", "--group", "R2", *both)
    assert result.exit_code == 0, result.output
    status = _positions(invoke(ports, "status", "--json"))
    assert max(abs(a - float(b)) for a, b in zip(status, both, strict=True)) < 1e-3
    only = json.loads(invoke(ports, "status", "--json", "--group", "R2").stdout)
    assert [g["name"] for g in only["groups"]] == ["R2"]


def test_unknown_group_is_one_line_with_the_groups(two_arms: tuple[Sim, Path]) -> None:
    _, ports = two_arms
    result = invoke(ports, "move", "0", "0", "0", "0", "0", "0", "--group", "R3")
    assert result.exit_code == EXIT_USAGE
    assert result.stderr.count("\n") == 1
    assert "no group 'R3'" in result.stderr
    assert "R1 (group 0, 6 axes), R2 (group 1, 6 axes)" in result.stderr
    assert "Traceback" not in result.output
    result = invoke(ports, "tool", "3", "--group", "R2", "--robot", "gp12")
    assert "warning: --robot is ignored: the cell file" in result.stderr
    assert result.exit_code == 0, result.output
    result = invoke(ports, "tool", "3", "--group", "2")
    assert result.exit_code == EXIT_USAGE
    assert "no group 2" in result.stderr
    assert "group 1 (R2) moves with tool 3" in invoke(ports, "tool", "3", "--group", "r2").stdout


def test_single_arm_model_against_two_arms_is_a_mismatch(two_arms: tuple[Sim, Path]) -> None:
    _, ports = two_arms
    result = invoke(
        _ports_only(ports),
        "status",
        env={"PYMOTOROS_CONFIG": ""},
    )
    assert result.exit_code == EXIT_USAGE
    assert "model mismatch" in result.stderr
    assert "also streams group(s) 1" in result.stderr


def test_group_1_without_a_cell_names_the_cell_option(two_arms: tuple[Sim, Path]) -> None:
    _, ports = two_arms
    result = invoke(
        _ports_only(ports),
        *("move", "0", "0", "0", "0", "0", "0", "--group", "1"),
        env={"PYMOTOROS_CONFIG": ""},
    )
    assert result.exit_code == EXIT_USAGE
    assert "no group 1" in result.stderr
    assert "--config CELL.toml" in result.stderr
    assert "Traceback" not in result.output


def test_reset_servo_and_verbose_requests(two_arms: tuple[Sim, Path]) -> None:
    _, ports = two_arms
    result = invoke(ports, "-v", "servo", "off")
    assert result.exit_code == 0, result.output
    assert result.stdout.strip() == "servo power off"
    lines = [ln for ln in result.stderr.splitlines() if "pymotoros.client.requests" in ln]
    # STOP_MOTION on connecting (docs/client.md), then STOP_SERVOS: each with its reply
    assert len(lines) == 4
    assert "->" in lines[0]
    assert "200111" in lines[0]  # STOP_MOTION
    assert "->" in lines[2]
    assert "MotoMotionCtrl" in lines[2]
    assert "200113" in lines[2]  # STOP_SERVOS
    assert "<-" in lines[3]
    assert "MotoMotionReply" in lines[3]
    status = json.loads(invoke(ports, "status", "--json").stdout)["status"]
    assert status["drives_powered"] is False
    assert invoke(ports, "servo", "on").stdout.strip() == "servo power on"
    assert invoke(ports, "reset").stdout.strip() == "alarms and errors reset"


def _spawn_move(ports: Path, *values: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYMOTOROS_PORTS_FILE": str(ports), "PYMOTOROS_CONFIG": str(CELL)}
    return subprocess.Popen(  # noqa: S603 - our own CLI
        [sys.executable, "-m", "pymotoros", "move", "--group", "R1", *values],
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )


def test_sigterm_mid_move_stops_short_and_exits_143(two_arms: tuple[Sim, Path]) -> None:
    sim, ports = two_arms
    assert invoke(ports, "enable").exit_code == 0
    assert invoke(ports, "move", "--group", "R1", "0", "0", "0", "0", "0", "0").exit_code == 0
    goal = 2.5
    with SyncRobotClient(cell=CELL, **sim.client_options()) as watcher:
        watcher.wait_for_state()
        process = _spawn_move(ports, str(goal), "0", "0", "0", "0", "0")
        try:
            watcher.wait_until(lambda s: (s.positions(0) or (0,))[0] > 0.2, 30.0, "motion")
            # a second motion client is refused while the robot moves: stop explains
            result = invoke(ports, "stop")
            assert result.exit_code == EXIT_CONNECTION
            # the rule and the remedies once: the library's text, then what stop adds
            error = [ln for ln in result.stderr.splitlines() if ln.startswith("error: ")]
            assert len(error) == 1, result.stderr
            # the library states the rule (closed before any reply); a reset connection
            # does not, and then stop states it
            rules = ("MotoROS takes one motion connection", "MotoROS allows one motion client")
            assert sum(error[0].count(rule) for rule in rules) == 1, error[0]
            assert error[0].count("Ctrl-C") == 1, error[0]
            assert "`pymotoros stop` cannot take over" in error[0]
            assert "SIGTERM" in error[0]
            assert f"http://127.0.0.1:{sim.http}" in result.stderr
            process.send_signal(signal.SIGTERM)
            _, stderr = process.communicate(timeout=SIGTERM_WAIT_S)
        finally:
            if process.poll() is None:
                process.kill()
                process.communicate()
        assert process.returncode == EXIT_TERMINATED, stderr
        assert "Traceback" not in stderr
        assert "stopped (STOP_MOTION) at [" in stderr
        # said once, by the CLI's own line: not again in a log line of the client's stop
        assert stderr.count("STOP_MOTION") == 1, stderr
        assert "" not in stderr.splitlines(), stderr
        assert "short of the goal" in stderr
        state = watcher.wait_until(lambda s: s.status is not None and not s.status.in_motion, 10.0)
        assert (state.positions(0) or (goal,))[0] < goal - 0.1
