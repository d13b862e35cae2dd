"""``pymotoros plan``/``check``/``run``/``plot``: exit codes, the --json contract, and a
trajectory as ``rostopic echo`` prints it checked, run on ``pymotoros sim`` and plotted."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, sim_fixture

from pymotoros.cli.main import cli
from pymotoros.models import controller_model, robot_model
from pymotoros.trajectory import check_trajectory, read_trajectory_file
from pymotoros.trajectory.check import EXIT_OK, EXIT_REFUSED, EXIT_WARNINGS
from pymotoros.trajectory.files import to_yaml
from pymotoros.trajectory.plot import plot_trajectory

matplotlib.use("Agg")

HC10 = robot_model("hc10")
YRC = controller_model("yrc1000")
CONTRACT = {"accepted", "refusal", "warnings", "duration_s", "increments"}
REFUSAL_KEYS = {"point", "axis", "value", "limit", "result", "subcode", "meaning", "remedy"}
WARNING_KEYS = {"kind", "point", "axis", "value", "limit", "text"}


def invoke(*args: str) -> Result:
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


sim = sim_fixture()


@pytest.fixture
def planned_yaml(tmp_path: Path) -> Path:
    """Waypoints timed by ``pymotoros plan``, written as ROS 1 rostopic echo YAML."""
    way = tmp_path / "way.csv"
    way.write_text("s,l,u,r,b,t\n0,0,0,0,0,0\n0.4,0.2,0.3,0,-0.5,0\n0,0,0,0,0,0\n")
    out = tmp_path / "traj.yaml"
    result = invoke("plan", str(way), "--speed-scale", "0.8", "-o", str(out))
    assert result.exit_code == 0, result.output
    return out


def _write_yaml(tmp_path: Path, times: list[float], pos: list[list[float]]) -> Path:
    from pymotoros.trajectory import Trajectory

    n = len(pos[0])
    traj = Trajectory(
        HC10.groups[0].joint_names, np.array(times), np.array(pos), np.zeros((len(pos), n))
    )
    path = tmp_path / "t.yaml"
    path.write_text(to_yaml(traj))
    return path


def test_check_accepted_json_contract(planned_yaml: Path) -> None:
    result = invoke("check", str(planned_yaml), "--json")
    assert result.exit_code == EXIT_OK, result.output
    data = json.loads(result.stdout)
    assert set(data) >= CONTRACT
    assert data["accepted"] is True
    assert data["refusal"] is None
    assert data["warnings"] == []
    traj = read_trajectory_file(planned_yaml)
    report = check_trajectory(traj, HC10, YRC)
    assert data["increments"] == report.increments > 0
    assert data["duration_s"] == pytest.approx(traj.duration, abs=0.005)


def test_check_refusal_exit_1_json_and_human(tmp_path: Path) -> None:
    path = _write_yaml(tmp_path, [0.0, 1.0], [[0.0] * 6, [0.1] + [0.0] * 5])
    result = invoke("check", str(path), "--json", "--from", "0,0,0.01,0,0,0")
    assert result.exit_code == EXIT_REFUSED
    data = json.loads(result.stdout)
    assert data["accepted"] is False
    assert set(data["refusal"]) == REFUSAL_KEYS
    assert data["refusal"]["subcode"] == 3011
    assert data["refusal"]["result"] == 3
    assert data["refusal"]["point"] == 0
    assert data["refusal"]["axis"] == "joint_3_u"
    human = invoke("check", str(path), "--from", "0,0,0.01,0,0,0")
    assert human.exit_code == EXIT_REFUSED
    assert "REFUSED" in human.stdout
    assert "3011" in human.stdout
    assert "remedy:" in human.stdout


def test_check_warnings_exit_4(tmp_path: Path) -> None:
    path = _write_yaml(tmp_path, [0.0, 0.3], [[0.0] * 6, [0.0, 0.0, 0.0, 0.5, 0.0, 0.0]])
    result = invoke("check", str(path), "--json")
    assert result.exit_code == EXIT_WARNINGS
    data = json.loads(result.stdout)
    assert data["accepted"] is True
    assert [set(w) for w in data["warnings"]] == [WARNING_KEYS]
    assert data["warnings"][0]["kind"] == "acceleration"
    assert data["warnings"][0]["axis"] == "joint_4_r"


def test_check_usage_errors_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("joint_names: [x]\npoints: []\n")
    result = invoke("check", str(bad))
    assert result.exit_code == 2
    assert "points must be a non-empty list" in result.output
    good = _write_yaml(tmp_path, [0.0, 1.0], [[0.0] * 6] * 2)
    assert invoke("check", str(good), "--from", "0,0").exit_code == 2


def test_rostopic_echo_yaml_checked_run_and_plotted(
    sim: Sim, planned_yaml: Path, tmp_path: Path
) -> None:
    assert invoke("check", str(planned_yaml)).exit_code == EXIT_OK
    assert invoke("move", "0", "0", "0", "0", "0", "0", "--enable", *sim.cli_args()).exit_code == 0
    result = invoke("run", str(planned_yaml), "--json", *sim.cli_args())
    assert result.exit_code == 0, result.output
    final = json.loads(result.stdout)["positions"]
    assert np.allclose(final, [0.0] * 6, atol=1e-4)
    png = tmp_path / "plot.png"
    result = invoke("plot", str(planned_yaml), "-o", str(png))
    assert result.exit_code == 0, result.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_run_refuses_to_start_when_check_fails(sim: Sim, tmp_path: Path) -> None:
    path = _write_yaml(tmp_path, [0.0, 0.3], [[0.0] * 6, [0.0, 0.0, 0.0, 0.5, 0.0, 0.0]])
    result = invoke("run", str(path), *sim.cli_args())
    assert result.exit_code == EXIT_WARNINGS
    assert "not started" in result.stderr


def test_plot_content(planned_yaml: Path, tmp_path: Path) -> None:
    traj = read_trajectory_file(planned_yaml)
    report = check_trajectory(traj, HC10, YRC)
    fig = plot_trajectory(traj, HC10, YRC, report, tmp_path / "p.png")
    axes = fig.get_axes()
    assert len(axes) == 2 * 6
    position = axes[0]  # joint_1_s position
    labels = [line.get_label() for line in position.get_lines()]
    assert {"planned points", "MotoROS interpolation"} <= set(labels)
    # joint_1_s swings 0.4 rad: its limits (±3.14 rad) are off the scale, and said so
    assert "joint limits" not in labels
    assert any("off the scale" in text.get_text() for text in position.texts)
    planned, interp = position.get_lines()[0], position.get_lines()[1]
    assert np.allclose(planned.get_xdata(), traj.times)
    assert len(interp.get_xdata()) == report.increments + 1
    assert max(interp.get_ydata()) == pytest.approx(0.4, abs=1e-4)  # the waypoint
    assert position.get_ylabel().startswith("joint_1_s")
    assert "[rad]" in position.get_ylabel()
    assert axes[1].get_ylabel() == "[rad/s]"
    # the velocity limit of joint_1_s: a dashed line if within the panel, else a note
    vmax = HC10.groups[0].axes[0].max_velocity
    vlines = [line for line in axes[1].get_lines() if line.get_label() == "velocity limit"]
    if vlines:
        assert abs(vlines[0].get_ydata()[0]) == pytest.approx(vmax)
    else:
        assert any(f"{vmax:.3g}" in text.get_text() for text in axes[1].texts)
    title = fig.get_suptitle()
    assert "hc10" in title
    assert "yrc1000" in title
    assert f"{report.duration_s:.3f} s" in title


FSU_CELL = """name = "slow cell"
[controller]
model = "yrc1000"
fsu_speed_limit_pct = 30
[robot]
model = "hc10"
"""


@pytest.fixture
def fsu_cell(tmp_path: Path) -> Path:
    path = tmp_path / "slow.toml"
    path.write_text(FSU_CELL)
    return path


def test_check_config_uses_the_cells_fsu_limit(planned_yaml: Path, fsu_cell: Path) -> None:
    built_in = invoke("check", str(planned_yaml), "--json")
    assert built_in.exit_code == EXIT_OK
    result = invoke("check", str(planned_yaml), "--config", str(fsu_cell), "--json")
    assert result.exit_code == EXIT_WARNINGS, result.output
    data = json.loads(result.stdout)
    assert set(data) >= CONTRACT
    assert [w["kind"] for w in data["warnings"]] == ["fsu"]
    assert set(data["warnings"][0]) == WARNING_KEYS
    assert data["increments"] > json.loads(built_in.stdout)["increments"]
    human = invoke("check", str(planned_yaml), "--config", str(fsu_cell))
    assert human.exit_code == EXIT_WARNINGS
    assert "cell 'slow cell' (hc10 on yrc1000, FSU joint speeds 30 %)" in human.stdout
    assert "warning [fsu]" in human.stdout
    # plot draws what the FSU lets through: as many ticks as check predicts
    png = planned_yaml.with_suffix(".png")
    assert (
        invoke("plot", str(planned_yaml), "--config", str(fsu_cell), "-o", str(png)).exit_code == 0
    )


@pytest.mark.parametrize(
    ("command", "models"),
    [
        ("check", ["--robot", "hc10"]),
        ("check", ["--controller", "dx200"]),
        ("plot", ["--robot", "hc10", "--controller", "yrc1000"]),
        ("run", ["--robot", "hc10"]),
    ],
)
def test_config_with_controller_or_robot_is_a_usage_error(
    command: str, models: list[str], planned_yaml: Path, fsu_cell: Path, tmp_path: Path
) -> None:
    extra = ["-o", str(tmp_path / "x.png")] if command == "plot" else []
    result = invoke(command, str(planned_yaml), "--config", str(fsu_cell), *models, *extra)
    assert result.exit_code == 2
    assert "cannot be combined with --config" in result.output
    assert models[0] in result.output


def test_plan_config_with_robot_is_a_usage_error_and_warns_about_the_fsu(
    fsu_cell: Path, tmp_path: Path
) -> None:
    way = tmp_path / "way.csv"
    way.write_text("0,0,0,0,0,0\n0.4,0.2,0.3,0,-0.5,0\n")
    out = tmp_path / "t.json"
    bad = invoke("plan", str(way), "--config", str(fsu_cell), "--robot", "hc10", "-o", str(out))
    assert bad.exit_code == 2
    assert "--robot cannot be combined with --config" in bad.output
    result = invoke("plan", str(way), "--config", str(fsu_cell), "-o", str(out))
    assert result.exit_code == 0, result.output
    assert "FSU limits joint speeds to 30 %" in result.stderr
    assert invoke("check", str(out), "--config", str(fsu_cell)).exit_code == EXIT_WARNINGS
    slow = tmp_path / "slow.json"
    args = ["--speed-scale", "0.25", "-o", str(slow)]
    result = invoke("plan", str(way), "--config", str(fsu_cell), *args)
    assert result.exit_code == 0
    assert "FSU" not in result.stderr
    assert invoke("check", str(slow), "--config", str(fsu_cell)).exit_code == EXIT_OK


def test_check_config_errors_name_the_file(planned_yaml: Path, tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[controller]\nfsu_speed_limit_pct = 0\n")
    result = invoke("check", str(planned_yaml), "--config", str(bad))
    assert result.exit_code == 2
    assert "controller.fsu_speed_limit_pct: must lie in 1..100, not 0" in result.output
    two = tmp_path / "two.toml"
    two.write_text('[[groups]]\nrobot = "hc10"\n[[groups]]\nrobot = "hc10"\n')
    result = invoke("check", str(planned_yaml), "--config", str(two))
    assert result.exit_code == 2
    assert "joint_1_s belongs to groups R1, R2" in result.output


LAG_PLAUSIBLE_MS = (4.0, 100.0)
"""A feedback lag on the twin: at least one tick (the twin's feedback trails the command by
3 ticks on average, plus the ticks before the first increment), far below 100 ms."""
FEEDBACK_PEAK_TOLERANCE = 5e-3
"""rad: the twin's feedback is the command averaged over 7 ticks, which rounds a peak off
by far less than this."""


def test_plot_with_a_recording_of_a_run_on_the_sim(
    sim: Sim, planned_yaml: Path, tmp_path: Path
) -> None:
    from pymotoros.cli.trajectory import recorded_run
    from pymotoros.trajectory.plot import COMMANDED_LABEL, ERROR_LABEL, hermite, tracking

    rec = tmp_path / "run.pcapng"
    assert invoke("move", "0", "0", "0", "0", "0", "0", "--enable", *sim.cli_args()).exit_code == 0
    result = invoke("run", str(planned_yaml), "--record", str(rec), *sim.cli_args())
    assert result.exit_code == 0, result.output
    png = tmp_path / "rec.png"
    result = invoke("plot", str(planned_yaml), "--recording", str(rec), "-o", str(png))
    assert result.exit_code == 0, result.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "joint_1_s: feedback lag" in result.stdout
    assert "joint_4_r" not in result.stdout  # still: no lag to measure

    # the figure the command drew, inspected
    traj = read_trajectory_file(planned_yaml)
    report = check_trajectory(traj, HC10, YRC)
    run = recorded_run(rec, traj, HC10)
    fig = plot_trajectory(traj, HC10, YRC, report, tmp_path / "again.png", run=run)
    axes = fig.get_axes()
    assert len(axes) == 3 * 6
    assert "recording run.pcapng: feedback lag" in fig.get_suptitle()
    moving = [j for j in range(6) if np.ptp(traj.positions[:, j]) > 0]
    assert moving == [0, 1, 2, 4]
    for j in range(6):
        position, error_panel = axes[3 * j], axes[3 * j + 2]
        lines = {line.get_label(): line for line in position.get_lines()}
        commanded = lines[COMMANDED_LABEL]
        np.testing.assert_allclose(commanded.get_xdata(), traj.times, atol=1e-6)
        np.testing.assert_allclose(commanded.get_ydata(), traj.positions[:, j], atol=1e-6)
        [feedback] = [line for label, line in lines.items() if label.startswith("feedback (")]
        fb = np.asarray(feedback.get_ydata())
        assert fb.min() == pytest.approx(traj.positions[:, j].min(), abs=FEEDBACK_PEAK_TOLERANCE)
        assert fb.max() == pytest.approx(traj.positions[:, j].max(), abs=FEEDBACK_PEAK_TOLERANCE)
        assert fb[-1] == pytest.approx(traj.positions[-1, j], abs=1e-4)  # settled at the end
        track = tracking(run, j)
        assert track is not None
        assert np.isfinite(track.max_error)
        assert track.max_error >= track.mean_error >= 0
        [error] = error_panel.get_lines()[:1]
        assert error.get_label().startswith(ERROR_LABEL)
        if j in moving:
            assert track.lag_ms is not None
            assert LAG_PLAUSIBLE_MS[0] <= track.lag_ms <= LAG_PLAUSIBLE_MS[1]
            assert f"lag {track.lag_ms:.0f} ms" in feedback.get_label()
            # the error is mostly the feedback lagging the command: taking the lag out
            # of the command shrinks it
            assert 0 < track.max_error < np.ptp(traj.positions[:, j])
            cmd, fbs = run.commanded[0], run.feedback[0]
            t = fbs.times[(fbs.times >= 0) & (fbs.times <= traj.times[-1])]
            f = fbs.positions[(fbs.times >= 0) & (fbs.times <= traj.times[-1]), j]
            args = (cmd.times, cmd.positions[:, j], cmd.velocities[:, j])
            shifted = np.abs(f - hermite(*args, t - track.lag_ms / 1000)).max()
            assert shifted < track.max_error / 2
        else:
            assert track.lag_ms is None
            assert "lag n/a" in feedback.get_label()
            assert track.max_error == pytest.approx(0.0, abs=1e-6)


def test_plot_recording_without_a_trajectory_is_a_usage_error(
    sim: Sim, planned_yaml: Path, tmp_path: Path
) -> None:
    rec = tmp_path / "io.pcapng"
    assert invoke("io", "read", "10010", "--record", str(rec), *sim.cli_args()).exit_code == 0
    result = invoke(
        "plot", str(planned_yaml), "--recording", str(rec), "-o", str(tmp_path / "x.png")
    )
    assert result.exit_code == 2
    assert "holds no trajectory point the controller accepted" in result.output


def test_run_with_a_cell_refuses_what_the_cell_would_slow_down_unless_forced(
    sim: Sim, planned_yaml: Path, fsu_cell: Path
) -> None:
    """``run --config``: the pre-flight uses the cell (FSU at 30 %) even though the twin it
    talks to has no FSU; the refusal leaves the robot where it was, --force runs it."""
    assert invoke("move", "0", "0", "0", "0", "0", "0", "--enable", *sim.cli_args()).exit_code == 0
    refused = invoke("run", str(planned_yaml), "--config", str(fsu_cell), *sim.cli_args())
    assert refused.exit_code == EXIT_WARNINGS
    assert "not started" in refused.stderr
    assert "fsu" in refused.stderr
    forced = invoke(
        "run", str(planned_yaml), "--config", str(fsu_cell), "--force", "--json", *sim.cli_args()
    )
    assert forced.exit_code == 0, forced.output
    assert np.allclose(json.loads(forced.stdout)["positions"], [0.0] * 6, atol=1e-4)


CELLS = Path(__file__).resolve().parents[2] / "examples" / "cells"
FIXTURE_CELL = CELLS / "hc10_table_fixture.toml"


def _tick_csv(tmp_path: Path, offset_s: float = 0.0) -> Path:
    """A slow S-axis sweep sampled at exactly one 4 ms tick, as a CSV (no robot name in it)."""
    n = 60
    times = np.arange(n) * 0.004 + offset_s
    pos = np.zeros((n, 6))
    pos[:, 0] = np.linspace(0.0, 0.003, n)
    vel = np.zeros((n, 6))
    vel[1:-1, 0] = 0.003 / ((n - 1) * 0.004)
    rows = ["time,p1,p2,p3,p4,p5,p6,v1,v2,v3,v4,v5,v6"]
    rows += [
        ",".join(repr(float(x)) for x in (t, *p, *v))
        for t, p, v in zip(times, pos, vel, strict=True)
    ]
    path = tmp_path / "ticks.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_check_config_of_a_csv_does_not_take_the_cell_for_its_maker(tmp_path: Path) -> None:
    """Issue 29 item 5: a CSV names no robot, so ``check --config`` has nobody to warn about
    (it warned "was made for HC10 on a table; checking it against the cell HC10 on a table")."""
    result = invoke("check", str(_tick_csv(tmp_path)), "--config", str(FIXTURE_CELL))
    assert "was made for" not in result.stderr, result.stderr
    assert "cell 'HC10 on a table'" in result.stdout  # it was checked against the cell


def test_check_explains_the_whole_millisecond_truncation(tmp_path: Path) -> None:
    """Issue 29 item 5: a file sampled at exactly 4 ms loses a millisecond now and then to
    MotoROS's truncation of the float32 time (reference §3.4, §11); the message says so, with
    the numbers, the rule, and what to do; doing it clears the warning."""
    result = invoke("check", str(_tick_csv(tmp_path)), "--robot", "hc10")
    assert result.exit_code == EXIT_WARNINGS, result.output
    text = result.stdout
    assert "less than one 4 ms tick (first: point 5, 3 ms after point 4)" in text
    assert "the file spaces them 4 ms apart" in text
    assert "truncates each point's float32 time to whole milliseconds" in text
    assert "§3.4" in text
    assert "§11" in text
    assert "3.999999 ms is truncated to 3 ms" in text
    assert "add 0.0005 s to each time" in text
    fixed = invoke("check", str(_tick_csv(tmp_path, offset_s=0.0005)), "--robot", "hc10")
    assert "tick" not in fixed.stdout, fixed.stdout
    assert fixed.exit_code == EXIT_OK, fixed.output


def test_check_names_a_gap_the_file_itself_makes_too_short(tmp_path: Path) -> None:
    """Points really closer than a tick are not blamed on the truncation."""
    path = _tick_csv(tmp_path)
    lines = path.read_text().splitlines()
    # point 1 at 0.007 s: point 2 (0.008 s) follows it by 1 ms in the file itself
    cells = lines[2].split(",")
    lines[2] = ",".join(["0.007", *cells[1:]])
    path.write_text("\n".join(lines) + "\n")
    text = invoke("check", str(path), "--robot", "hc10").stdout
    assert "(first: point 2, 1 ms after point 1); the file itself spaces them 1 ms apart" in text
    assert "sample it at 4 ms or more" in text
    assert "truncat" not in text


def test_ctrl_c_during_run_says_where_the_robot_stopped(sim: Sim, tmp_path: Path) -> None:
    """``pymotoros run`` interrupted: the client stops the robot, and the one line about
    it says where it stands (the client's own log line of the stop is left to the CLI)."""
    import os
    import signal
    import subprocess

    from pymotoros.client import SyncRobotClient

    way = tmp_path / "way.csv"
    way.write_text("s,l,u,r,b,t\n0,0,0,0,0,0\n2.0,0,0,0,0,0\n")
    slow = tmp_path / "slow.yaml"
    planned = invoke("plan", str(way), "--speed-scale", "0.2", "-o", str(slow))
    assert planned.exit_code == 0, planned.output
    assert invoke("move", "0", "0", "0", "0", "0", "0", "--enable", *sim.cli_args()).exit_code == 0
    with SyncRobotClient(**sim.client_options()) as watcher:
        watcher.wait_for_state()
        process = subprocess.Popen(  # noqa: S603 - our own CLI
            [sys.executable, "-m", "pymotoros", "run", str(slow), *sim.cli_args()],
            stderr=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            env={**os.environ},
        )
        try:
            watcher.wait_until(lambda s: (s.positions(0) or (0,))[0] > 0.2, 30.0, "motion")
            process.send_signal(signal.SIGINT)
            _, stderr = process.communicate(timeout=30)
        finally:
            if process.poll() is None:
                process.kill()
                process.communicate()
        rest = watcher.wait_until(lambda s: s.status is not None and not s.status.in_motion, 10.0)
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr
    assert stderr.count("stands at [") == 1, stderr
    assert "WARNING" not in stderr, stderr  # a plain line, not a log record
    told = re.search(r"stopped \(STOP_MOTION\) and stands at \[([^\]]+)\] rad", stderr)
    assert told is not None, stderr
    here = [float(v) for v in told.group(1).split(",")]
    assert here == pytest.approx(list(rest.positions(0) or ()), abs=2e-4)
    assert here[0] < 2.0 - 0.1  # stopped short of the goal
