"""CLI options from flags, PYMOTOROS_* variables and a settings file.

Precedence: flag > env > file > default.
"""

from __future__ import annotations

import contextlib
import json
import sys
from pathlib import Path

from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_CONNECTION, EXIT_USAGE

sim = sim_fixture()


def closed_port() -> int:
    """A port nothing listens on (bound then released)."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def run(args: list[str], env: dict[str, str], cwd: Path) -> Result:
    """Run the CLI in ``cwd`` (so no ./pymotoros.toml of the repository is read)."""
    with contextlib.chdir(cwd):
        return CliRunner().invoke(cli, args, env={"PYMOTOROS_SETTINGS": "", **env})


def ports_env(sim: Sim) -> dict[str, str]:
    return {
        "PYMOTOROS_MOTION_PORT": str(sim.motion),
        "PYMOTOROS_STATE_PORT": str(sim.state),
        "PYMOTOROS_IO_PORT": str(sim.io),
    }


def test_environment_alone_finds_the_twin(sim: Sim, tmp_path: Path) -> None:
    result = run(["mreg", "read", "3", "--json"], ports_env(sim), tmp_path)
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["number"] == 3


def test_command_options_from_the_environment(sim: Sim, tmp_path: Path) -> None:
    env = {**ports_env(sim), "PYMOTOROS_STATUS_JSON": "1"}
    result = run(["status"], env, tmp_path)
    assert result.exit_code == 0, result.output
    assert "groups" in json.loads(result.stdout)
    env = {**ports_env(sim), "PYMOTOROS_IO_READ_JSON": "true"}
    result = run(["io", "read", "10010"], env, tmp_path)
    assert json.loads(result.stdout) == {"address": 10010, "value": 0}


def test_settings_file_and_precedence(sim: Sim, tmp_path: Path) -> None:
    settings = tmp_path / "settings.toml"
    settings.write_text(
        f"host = '127.0.0.1'\nmotion_port = {sim.motion}\nstate-port = {sim.state}\n"
        f"io_port = {sim.io}\ntimeout = 3\n[status]\njson = true\n"
    )
    env = {"PYMOTOROS_SETTINGS": str(settings)}
    result = run(["status"], env, tmp_path)
    assert result.exit_code == 0, result.output
    assert "groups" in json.loads(result.stdout)  # [status] json = true from the file
    dead = str(closed_port())
    # env beats file: a dead port from the environment fails the connection
    result = run(["mreg", "read", "1"], {**env, "PYMOTOROS_IO_PORT": dead}, tmp_path)
    assert result.exit_code == EXIT_CONNECTION
    assert dead in result.stderr
    # flag beats env
    args = ["mreg", "read", "1", "--io-port", str(sim.io)]
    result = run(args, {**env, "PYMOTOROS_IO_PORT": dead}, tmp_path)
    assert result.exit_code == 0, result.output


def test_local_pymotoros_toml_is_read(sim: Sim, tmp_path: Path) -> None:
    (tmp_path / "pymotoros.toml").write_text(f"io_port = {sim.io}\n")
    with contextlib.chdir(tmp_path):
        result = CliRunner().invoke(cli, ["mreg", "read", "2"], env={"PYMOTOROS_SETTINGS": ""})
    assert result.exit_code == 0, result.output


def test_settings_mistakes_are_named(tmp_path: Path) -> None:
    settings = tmp_path / "bad.toml"
    settings.write_text("speed_scale = 0.5\n")
    result = run(["status"], {"PYMOTOROS_SETTINGS": str(settings)}, tmp_path)
    assert result.exit_code == EXIT_USAGE
    assert "speed_scale: not an option every command shares" in result.stderr
    settings.write_text("[move]\nspeed = 0.5\n")
    result = run(["move", "0"], {"PYMOTOROS_SETTINGS": str(settings)}, tmp_path)
    assert result.exit_code == EXIT_USAGE
    assert "[move] speed: the command has no such option" in result.stderr
    settings.write_text("[mvoe]\nspeed_scale = 0.5\n")
    result = run(["status"], {"PYMOTOROS_SETTINGS": str(settings)}, tmp_path)
    assert result.exit_code == EXIT_USAGE
    assert "[mvoe]: no such command" in result.stderr
    result = run(["status"], {"PYMOTOROS_SETTINGS": str(tmp_path / "missing.toml")}, tmp_path)
    assert result.exit_code == EXIT_USAGE
    assert "no such file" in result.stderr


def test_ports_file_missing_says_how_to_make_it(tmp_path: Path) -> None:
    result = run(["status", "--ports-file", str(tmp_path / "p.json")], {}, tmp_path)
    assert result.exit_code == EXIT_USAGE
    assert "pymotoros sim --ports-file" in result.stderr
    assert "Traceback" not in result.output


def test_ports_file_is_written_when_ready_and_removed_on_exit(tmp_path: Path) -> None:
    ports = tmp_path / "ports.json"
    with running_sim("--ports-file", str(ports)) as the_sim:
        assert json.loads(ports.read_text())["motion"] == the_sim.motion
    assert the_sim.process.returncode == 0
    assert not ports.exists()
