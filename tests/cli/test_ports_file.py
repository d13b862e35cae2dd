"""The ports file carries each cell (issue 20 item 8), and the small config errors
(item 10): the role of a port in use, the name of a bad environment variable.

The FS100/SDA10F case runs a real ``pymotoros sim`` subprocess on port 0 and the robot
commands as subprocesses too, so what they log on stderr is what a user sees: before,
``status`` through this ports file logged an ERROR with a hex dump (it spoke
little-endian to a big-endian controller) unless ``--controller``/``--robot`` were
repeated. The two-cell case is in ``test_sim_cells.py``.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.ports_file import ports_file_target, read_ports_file_cell
from pymotoros.errors import ConfigError

COMMAND_TIMEOUT_S = 60.0
SDA10F_GROUPS = ["R1", "R2", "B1", "B2"]


@pytest.fixture(scope="module")
def sda10f(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Sim, Path]]:
    ports = tmp_path_factory.mktemp("ports") / "ports.json"
    with running_sim("--controller", "fs100", "--robot", "sda10f", "--ports-file", str(ports)) as s:
        yield s, ports


def pymotoros(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``pymotoros ARGS`` as a user runs it, without any PYMOTOROS_* of the test's shell."""
    clean = {k: v for k, v in os.environ.items() if not k.startswith("PYMOTOROS_")}
    return subprocess.run(  # noqa: S603 - our own interpreter and CLI
        [sys.executable, "-m", "pymotoros", *args],
        capture_output=True,
        text=True,
        timeout=COMMAND_TIMEOUT_S,
        check=False,
        env={**clean, **(env or {})},
    )


def test_the_ports_file_says_what_the_cell_is(sda10f: tuple[Sim, Path]) -> None:
    sim, ports = sda10f
    data = json.loads(ports.read_text())
    assert {k: data[k] for k in ("motion", "state", "io", "http")} == {
        "motion": sim.motion,
        "state": sim.state,
        "io": sim.io,
        "http": sim.http,
    }
    (cell,) = data["cells"]
    assert cell["controller"] == "fs100"
    assert cell["robots"] == ["sda10f"]
    assert [g["name"] for g in cell["groups"]] == SDA10F_GROUPS
    assert {g["robot"] for g in cell["groups"]} == {"sda10f"}
    assert cell["config"] is None
    told = read_ports_file_cell(ports)
    assert told.models is not None
    assert told.models.controller.type.value == "fs100"
    assert [g.name for g in told.models.robot.groups] == SDA10F_GROUPS


def test_status_through_the_ports_file_needs_no_models(sda10f: tuple[Sim, Path]) -> None:
    _, ports = sda10f
    done = pymotoros("status", "--json", "--ports-file", str(ports))
    assert done.returncode == 0, done.stderr
    assert "ERROR" not in done.stderr, done.stderr
    assert "mismatch" not in done.stderr, done.stderr
    groups = json.loads(done.stdout)["groups"]
    assert len(groups) == len(SDA10F_GROUPS)


def test_enable_move_and_io_through_the_ports_file(sda10f: tuple[Sim, Path]) -> None:
    """Motion and IO commands speak big-endian to the FS100 and know its four groups."""
    _, ports = sda10f
    env = {"PYMOTOROS_PORTS_FILE": str(ports)}
    done = pymotoros("enable", env=env)
    assert done.returncode == 0, done.stderr
    done = pymotoros("move", "--group", "B1", "0.1", env=env)
    assert done.returncode == 0, done.stderr
    done = pymotoros("io", "read", "--json", "50073", env=env)  # servo power is on
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["value"] == 1
    for done in (pymotoros("disable", env=env), pymotoros("servo", "off", env=env)):
        assert done.returncode == 0, done.stderr
    assert "ERROR" not in done.stderr


def test_an_explicit_robot_is_ignored_with_a_warning(sda10f: tuple[Sim, Path]) -> None:
    _, ports = sda10f
    done = pymotoros("status", "--ports-file", str(ports), "--robot", "hc10")
    assert done.returncode == 0, done.stderr
    assert f"--robot is ignored: the ports file {ports}" in done.stderr


def test_a_ports_file_without_cells_still_reads(tmp_path: Path) -> None:
    """A file written before the ports file carried the cell: its ports, no models."""
    path = tmp_path / "old.json"
    path.write_text('{"motion": 1, "state": 2, "io": 3, "http": null}')
    told = read_ports_file_cell(path)
    assert told.ports == {"motion": 1, "state": 2, "io": 3}
    assert told.models is None
    with pytest.raises(ConfigError, match=r"lists no cells .* leave out --cell a"):
        read_ports_file_cell(path, "a")


def test_cell_without_a_ports_file_says_what_it_needs() -> None:
    assert ports_file_target(None, None).ports == {}
    with pytest.raises(ConfigError, match="--cell a chooses a cell of a ports file"):
        ports_file_target(None, "a")


def test_a_bad_cell_entry_is_refused_by_the_cell_reader(tmp_path: Path) -> None:
    path = tmp_path / "ports.json"
    entry = {"cell": "a", "motion": 1, "state": 2, "io": 3, "controller": "fs100"}
    path.write_text(json.dumps({**entry, "cells": [{**entry, "groups": [{"robot": "ur5"}]}]}))
    with pytest.raises(ConfigError, match=r"\(cell a\): groups\[0\]\.robot: unknown robot"):
        read_ports_file_cell(path)


# ----------------------------------------------------------------- issue 20 item 10


@pytest.mark.parametrize(
    ("flag", "role"),
    [
        ("--motion-port", "the MotoROS motion port"),
        ("--io-port", "the MotoROS io port"),
        ("--http-port", "the control API (http) port"),
    ],
)
def test_a_port_in_use_says_which_port_it_is(flag: str, role: str) -> None:
    ports = {f: "0" for f in ("--motion-port", "--state-port", "--io-port", "--http-port")}
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = str(taken.getsockname()[1])
        ports[flag] = port
        done = pymotoros("sim", *(x for pair in ports.items() for x in pair))
    assert done.returncode == 1, done.stderr
    assert f"{role} {port}: " in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_a_bad_environment_variable_is_named() -> None:
    result = CliRunner().invoke(cli, ["status"], env={"PYMOTOROS_MOTION_PORT": "abc"})
    assert result.exit_code == 2
    assert (
        "Invalid value for PYMOTOROS_MOTION_PORT (the environment variable of --motion-port)"
        in (result.stderr)
    )
    result = CliRunner().invoke(cli, ["move", "0"], env={"PYMOTOROS_MOVE_SPEED_SCALE": "x"})
    assert result.exit_code == 2
    assert "PYMOTOROS_MOVE_SPEED_SCALE (the environment variable of --speed-scale)" in (
        result.stderr
    )
    # typed on the command line, the flag is the right name (even with a variable set)
    result = CliRunner().invoke(
        cli, ["status", "--motion-port=abc"], env={"PYMOTOROS_MOTION_PORT": "1"}
    )
    assert result.exit_code == 2
    assert "Invalid value for '--motion-port'" in result.stderr


def test_a_bad_settings_value_is_named_by_its_key(tmp_path: Path) -> None:
    settings = tmp_path / "settings.toml"
    settings.write_text('timeout = "soon"\n')
    result = CliRunner().invoke(cli, ["status"], env={"PYMOTOROS_SETTINGS": str(settings)})
    assert result.exit_code == 2
    assert f"Invalid value for timeout in the settings file {settings} (--timeout)" in (
        result.stderr
    )


def test_the_settings_file_can_name_the_cell(tmp_path: Path) -> None:
    """``cell = "b"`` at the top of the settings file chooses, as --cell would: the
    command then tries cell b's ports (nobody listens: a connection error, exit 3)."""
    with socket.create_server(("127.0.0.1", 0)) as probe:
        free = probe.getsockname()[1]  # closed below: connecting to it is refused
    entry = {"motion": free, "state": free, "io": free, "http": None}
    cells = [{"cell": "a", **entry, "motion": 1}, {"cell": "b", **entry}]
    ports = tmp_path / "ports.json"
    ports.write_text(json.dumps({**entry, "cells": cells}))
    settings = tmp_path / "settings.toml"
    settings.write_text(f'ports_file = "{ports}"\ncell = "b"\ntimeout = 1\n')
    result = CliRunner().invoke(cli, ["status"], env={"PYMOTOROS_SETTINGS": str(settings)})
    assert result.exit_code == 3, result.output
    assert str(free) in result.stderr
    settings.write_text(f'ports_file = "{ports}"\n')
    result = CliRunner().invoke(cli, ["status"], env={"PYMOTOROS_SETTINGS": str(settings)})
    assert result.exit_code == 2, result.output
    assert "choose one with --cell NAME" in result.stderr
