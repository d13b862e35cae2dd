"""Every input error of issue 14: one line, numbers in the user's units, a remedy, the exit code."""

from __future__ import annotations

import re
import socket
import sys
from pathlib import Path

from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, estop_a_cli_move, port_options, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_REFUSED, EXIT_USAGE

ROOT = Path(__file__).resolve().parents[2]
SWING = ROOT / "examples" / "trajectories" / "hc10_swing.csv"
SWING_DEG = ROOT / "examples" / "trajectories" / "hc10_swing_deg.csv"
EXIT_TIMEOUT_S = 30.0
"""Bound on a subprocess's life in these tests."""


def _one_line_error(result: Result, code: int) -> str:
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0]


sim = sim_fixture()


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()])


# ------------------------------------------------------------------ interpolate


def test_interpolate_without_a_header_says_so(tmp_path: Path) -> None:
    body = SWING.read_text().splitlines()[1:]
    headless = tmp_path / "headless.csv"
    headless.write_text("\n".join(body) + "\n")
    result = CliRunner().invoke(cli, ["interpolate", str(headless)])
    line = _one_line_error(result, EXIT_USAGE)
    assert "row 1 holds numbers" in line
    assert "time,p1,p2,p3,p4,p5,p6,v1" in line


def test_interpolate_warns_about_impossible_points(tmp_path: Path) -> None:
    rows = SWING.read_text().splitlines()
    cells = rows[3].split(",")
    cells[1] = "9"  # 9 rad on joint 1: beyond the HC10's limit, and far too fast
    rows[3] = ",".join(cells)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(rows) + "\n")
    result = CliRunner().invoke(cli, ["interpolate", str(bad), "-o", str(tmp_path / "o.csv")])
    assert result.exit_code == 0, result.output
    assert "point 2: joint_1_s = 9 rad is beyond its limits [-3.142, 3.142] rad" in result.stderr
    assert "above its maximum" in result.stderr
    assert "rad/s" in result.stderr


def test_interpolate_o_says_where_it_wrote_and_deg_matches_rad(tmp_path: Path) -> None:
    out_rad, out_deg = tmp_path / "rad.csv", tmp_path / "deg.csv"
    result = CliRunner().invoke(cli, ["interpolate", str(SWING), "-o", str(out_rad)])
    assert result.exit_code == 0
    assert result.stderr.strip() == f"wrote 526 increments (6 axes, 41 points) to {out_rad}"
    result = CliRunner().invoke(cli, ["interpolate", "--deg", str(SWING_DEG), "-o", str(out_deg)])
    assert result.exit_code == 0, result.output
    rad = [list(map(int, r.split(","))) for r in out_rad.read_text().splitlines()[1:]]
    deg = [list(map(int, r.split(","))) for r in out_deg.read_text().splitlines()[1:]]
    assert len(rad) == len(deg)
    # the deg file is rounded to 6 decimals of a degree: within a few pulses of the rad file
    assert (
        max(
            abs(a - b) for ra, rb in zip(rad, deg, strict=True) for a, b in zip(ra, rb, strict=True)
        )
        <= 3
    )
    assert any(r[1] != 0 for r in rad)


# ------------------------------------------------------------------ move


def test_nan_is_not_a_number_not_out_of_limits(sim: Sim) -> None:
    line = _one_line_error(invoke(sim, "move", "nan", "0", "0", "0", "0", "0"), EXIT_USAGE)
    assert "joint_1_s: nan is not a number" in line
    assert "rad" in line


def test_deg_limits_are_in_degrees(sim: Sim) -> None:
    line = _one_line_error(invoke(sim, "move", "--deg", "0", "0", "400", "0", "0", "0"), EXIT_USAGE)
    assert "joint_3_u: 400 deg is outside its limits" in line
    assert "deg; give a value within them" in line
    line = _one_line_error(invoke(sim, "move", "0", "0", "90", "0", "0", "0"), EXIT_USAGE)
    assert "90 rad" in line
    assert "--deg" in line


def test_deg_results_are_in_degrees(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    result = invoke(sim, "move", "--deg", "10", "0", "0", "0", "-20", "0")
    assert result.exit_code == 0, result.output
    reached = result.stdout.split("[")[1].split("]")
    values = [float(v) for v in reached[0].split(",")]
    assert reached[1].startswith(" deg in")
    assert abs(values[0] - 10) < 0.01
    assert abs(values[4] + 20) < 0.01


def test_wrong_model_is_a_mismatch_not_a_timeout(sim: Sim) -> None:
    line = _one_line_error(invoke(sim, "status", "--robot", "sda10f"), EXIT_USAGE)
    assert "model mismatch: sda10f expects 4 group(s)" in line
    assert "R1 7 axes" in line


def test_same_axes_other_model_is_found_by_its_dh_parameters(sim: Sim) -> None:
    line = _one_line_error(invoke(sim, "status", "--robot", "gp12", "--check-model"), EXIT_USAGE)
    assert "model mismatch: the controller's DH parameters are not gp12's" in line
    assert "d 0.2750 m on the controller, 0.4500 m in the model" in line
    assert "--robot hc10" in line
    assert invoke(sim, "status", "--check-model").exit_code == 0


def test_estop_mid_move_says_where_and_how_far(sim: Sim) -> None:
    assert invoke(sim, "enable").exit_code == 0
    assert invoke(sim, "move", "0", "0", "0", "0", "0", "0").exit_code == 0
    moved = estop_a_cli_move(sim, moving_beyond=0.2, timeout_s=EXIT_TIMEOUT_S)
    stderr = moved.stderr
    assert moved.returncode == EXIT_REFUSED, stderr
    assert "Traceback" not in stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    # the library stopped the robot and said where; the CLI adds only the distance left
    assert lines[0].count("stands at [") == 1, lines[0]
    assert re.search(
        r"stands at \[[^\]]+\] rad; \d+\.\d{4} rad short of the goal \(joint_1_s\)$", lines[0]
    )


# ------------------------------------------------------------------ sim


def test_busy_default_port_hints_port_0() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = CliRunner().invoke(
            cli,
            ["sim", *port_options(motion=port, state=0, io=0, http=0)],
        )
    assert result.exit_code == 1
    assert "Traceback" not in result.output
    assert "--motion-port 0" in result.stderr
    assert "--ports-file" in result.stderr
