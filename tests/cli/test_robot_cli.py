"""Every robot command of the CLI against ``pymotoros sim`` on port 0, and the exit codes."""

from __future__ import annotations

import json
import socket
import sys
from pathlib import Path

from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_CONNECTION, EXIT_REFUSED, EXIT_USAGE

SRDF = Path(__file__).resolve().parents[2] / "examples" / "hc10.srdf"


sim = sim_fixture()


def invoke(sim: Sim, *args: str) -> Result:
    """Run ``pymotoros ARGS --host … --motion-port …`` in process."""
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


def test_status_table_and_json(sim: Sim) -> None:
    table = invoke(sim, "status")
    assert table.exit_code == 0, table.output
    assert "joint_5_b" in table.output
    assert "motion possible" in table.output
    data = json.loads(invoke(sim, "status", "--json").stdout)
    assert set(data["status"]) >= {"drives_powered", "in_motion", "motion_possible", "mode"}
    assert data["groups"][0]["joints"][4] == "joint_5_b"
    assert len(data["groups"][0]["positions"]) == 6


def test_status_watch_prints_several_updates(sim: Sim) -> None:
    result = invoke(sim, "status", "--watch", "--json", "--count", "3", "--rate", "40")
    assert result.exit_code == 0
    assert len(result.stdout.strip().splitlines()) == 3


def test_move_before_enable_is_refused_with_remedy(sim: Sim) -> None:
    invoke(sim, "disable")
    result = invoke(sim, "move", "0", "0", "0", "0", "-1.57", "0")
    assert result.exit_code == EXIT_REFUSED
    assert "error:" in result.stderr
    assert "enable" in result.stderr
    assert "Traceback" not in result.stderr


def test_enable_move_named_and_joint_values(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    result = invoke(sim, "move", "0", "0", "0", "0", "-1.57", "0", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert abs(data["positions"][4] + 1.57) < 1e-3
    result = invoke(sim, "move", "--named", "pick", "--srdf", str(SRDF), "--speed-scale", "0.8")
    assert result.exit_code == 0, result.output
    assert "reached" in result.stdout
    result = invoke(sim, "move", "--deg", "10", "0", "0", "0", "-45", "0", "--json")
    assert abs(json.loads(result.stdout)["positions"][0] - 0.174533) < 1e-3
    assert invoke(sim, "move", "--named", "home").exit_code == 0


def test_move_usage_errors(sim: Sim) -> None:
    assert invoke(sim, "move").exit_code == EXIT_USAGE
    result = invoke(sim, "move", "1", "2")
    assert result.exit_code == EXIT_USAGE
    assert "joint_1_s" in result.stderr
    result = invoke(sim, "move", "--named", "nowhere")
    assert result.exit_code == EXIT_USAGE
    assert "home" in result.stderr
    result = invoke(sim, "move", "0", "0", "7", "0", "0", "0")
    assert result.exit_code == EXIT_USAGE
    assert "joint_3_u" in result.stderr


def test_stop_tool_disable(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    assert invoke(sim, "stop").stdout.strip() == "stopped"
    assert "tool 4" in invoke(sim, "tool", "4").stdout
    assert invoke(sim, "tool", "64").exit_code == EXIT_USAGE
    assert invoke(sim, "disable").exit_code == 0


def test_io_read_write(sim: Sim) -> None:
    assert invoke(sim, "io", "write", "10030", "1").exit_code == 0
    result = invoke(sim, "io", "read", "10030", "--json")
    assert json.loads(result.stdout) == {"address": 10030, "value": 1}
    assert invoke(sim, "io", "write", "1004", "165", "--group").exit_code == 0
    result = invoke(sim, "io", "read", "1004", "--group", "--json")
    assert json.loads(result.stdout) == {"address": 1004, "value": 165}
    assert invoke(sim, "io", "read", "10030").stdout.strip() == "1"


def test_io_address_checked_per_controller(sim: Sim) -> None:
    result = invoke(sim, "io", "write", "20010", "1")
    assert result.exit_code == EXIT_USAGE
    assert "external input" in result.stderr
    assert "10010-15127" in result.stderr
    result = invoke(sim, "io", "read", "10018")
    assert result.exit_code == EXIT_USAGE
    assert "0..7" in result.stderr


def test_mreg_read_write(sim: Sim) -> None:
    assert invoke(sim, "mreg", "write", "7", "300").exit_code == 0
    assert json.loads(invoke(sim, "mreg", "read", "7", "--json").stdout) == {
        "number": 7,
        "value": 300,
    }
    result = invoke(sim, "mreg", "write", "600", "1")
    assert result.exit_code == EXIT_USAGE
    assert "M000-M559" in result.stderr


def test_connection_refused_is_exit_3_in_one_line() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = str(s.getsockname()[1])
    result = CliRunner().invoke(cli, ["stop", "--motion-port", port, "--timeout", "2"])
    assert result.exit_code == EXIT_CONNECTION
    assert result.stderr.count("\n") == 1
    assert f"127.0.0.1:{port}" in result.stderr
    assert "refused" in result.stderr
    result = CliRunner().invoke(cli, ["stop", "--motion-port", port, "--debug"])
    assert "Traceback" in result.stderr


def test_help_documents_exit_codes() -> None:
    for command in ("status", "enable", "disable", "move", "stop", "tool"):
        result = CliRunner().invoke(cli, [command, "--help"])
        assert "Exit codes" in result.output
        assert "connection problem" in result.output
    assert "Exit codes" in CliRunner().invoke(cli, ["io", "read", "--help"]).output
    assert "Exit codes" in CliRunner().invoke(cli, ["mreg", "write", "--help"]).output
