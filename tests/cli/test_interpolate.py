"""``pymotoros interpolate``: the external contract, through click and as a process."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pymotoros.cli.main import cli
from pymotoros.models import controller_model, robot_model
from pymotoros.motion import GroupAxes, TrajPoint, interpolate

HEADER6 = "time,p1,p2,p3,p4,p5,p6,v1,v2,v3,v4,v5,v6\n"


def write(tmp_path: Path, text: str, name: str = "traj.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, ["interpolate", *args])
    return result.exit_code, result.stdout, result.stderr


def test_25ms_segment_with_pulses_per_rad(tmp_path: Path) -> None:
    traj = write(
        tmp_path,
        HEADER6 + "0,0,0,0,0,0,0,0,0,0,0,0,0\n0.0255,0.01,0,0,0,0,0,0,0,0,0,0,0\n",
    )
    code, out, _ = run(
        str(traj), "--controller", "yrc1000", "--robot", "hc10",
        "--pulses-per-rad", ",".join(["100000"] * 6),
    )  # fmt: skip
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == "time_ms,i1,i2,i3,i4,i5,i6"
    assert [line.split(",")[:2] for line in lines[1:]] == [
        ["4", "68"], ["8", "173"], ["12", "229"], ["16", "234"],
        ["20", "191"], ["24", "100"], ["25", "4"],
    ]  # fmt: skip


@pytest.mark.parametrize(("controller", "ms"), [("yrc1000", "699"), ("fs100", "700")])
def test_float_mode_follows_the_controller(tmp_path: Path, controller: str, ms: str) -> None:
    traj = write(tmp_path, HEADER6 + "0" + ",0" * 12 + "\n0.7,0.1" + ",0" * 11 + "\n")
    code, out, _ = run(str(traj), "--controller", controller)
    assert code == 0
    assert out.splitlines()[-1].split(",")[0] == ms


def test_output_file_equals_the_engine(tmp_path: Path) -> None:
    rows = [
        (0.0, [0.1, -0.2, 0.3, 0.0, 0.5, -0.6], [0.0] * 6),
        (0.25, [0.3, -0.1, 0.2, 0.1, 0.4, -0.5], [0.5, 0.2, -0.2, 0.3, -0.1, 0.2]),
        (0.61, [0.5, 0.0, 0.1, 0.2, 0.3, -0.4], [0.0] * 6),
    ]
    text = HEADER6 + "".join(",".join(map(repr, [t, *p, *v])) + "\n" for t, p, v in rows)
    traj = write(tmp_path, text)
    out_path = tmp_path / "out.csv"
    code, out, _ = run(str(traj), "-o", str(out_path))
    assert code == 0
    assert out == ""
    axes = GroupAxes.from_model(robot_model("hc10").groups[0], controller_model("yrc1000"))
    times, incs = interpolate([TrajPoint(t, tuple(p), tuple(v)) for t, p, v in rows], axes)
    expected = ["time_ms,i1,i2,i3,i4,i5,i6"] + [
        ",".join(map(str, [t, *row])) for t, row in zip(times.tolist(), incs.tolist(), strict=True)
    ]
    assert out_path.read_text(encoding="utf-8").splitlines() == expected


def test_seven_axis_output_is_in_controller_order(tmp_path: Path) -> None:
    header = (
        "time,"
        + ",".join(f"p{i}" for i in range(1, 8))
        + ","
        + ",".join(f"v{i}" for i in range(1, 8))
    )
    # only the E joint (ROS column p3) moves
    traj = write(tmp_path, header + "\n0" + ",0" * 14 + "\n0.1005,0,0,0.05" + ",0" * 11 + "\n")
    code, out, _ = run(str(traj), "--robot", "sia20d", "--controller", "dx100")
    assert code == 0
    rows = [list(map(int, line.split(","))) for line in out.splitlines()[1:]]
    assert all(r[1:7] == [0] * 6 for r in rows)
    assert sum(r[7] for r in rows) > 0


def test_a_refused_point_names_point_axis_value_limit_and_subcode(tmp_path: Path) -> None:
    traj = write(
        tmp_path,
        HEADER6 + "0" + ",0" * 12 + "\n0.1,0.1,0,0,0,0,0,0,0,0,4.0,0,0\n",
    )
    code, out, err = run(str(traj))
    assert code == 1
    assert out == ""
    message = err.strip().splitlines()[-1]
    for part in ("point 1", "joint_4_r", "4 rad/s", "3.14159 rad/s", "3013"):
        assert part in message


def test_the_speed_quirk_accepts_and_warns(tmp_path: Path) -> None:
    traj = write(tmp_path, HEADER6 + "0" + ",0" * 12 + "\n0.1,0.1,0,0,0,0,0,2.9,0,0,0,0,0\n")
    code, out, err = run(str(traj))
    assert code == 0
    assert "truncates |v|" in err
    assert len(out.splitlines()) > 1


BAD_CSV = [
    ("", ["empty"]),
    (HEADER6, ["no points"]),
    ("time,p1\n0,0\n", ["row 1", "13"]),
    (HEADER6 + "0,0,0\n", ["row 2", "3 columns", "13"]),
    (
        HEADER6 + "0" + ",0" * 12 + "\n0.1,0,0,abc" + ",0" * 9 + "\n",
        ["row 3", "column 4", "p3", "abc"],
    ),
    (HEADER6 + "0" + ",0" * 11 + ",nan\n", ["row 2", "column 13", "v6"]),
    (HEADER6 + "0" + ",0" * 11 + ",inf\n", ["row 2", "column 13", "v6"]),
]
"""Bad trajectory files and words their error must contain (both CSV paths)."""


@pytest.mark.parametrize(("text", "words"), BAD_CSV)
def test_bad_csv_is_a_clear_error(tmp_path: Path, text: str, words: list[str]) -> None:
    traj = write(tmp_path, text)
    code, _, err = run(str(traj))
    assert code == 2
    for word in words:
        assert word in err


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--robot", "sda10f"], ["single-group", "4 control groups"]),
        (["--robot", "nosuch"], ["unknown robot", "hc10"]),
        (["--controller", "nosuch"], ["--controller"]),
        (["--pulses-per-rad", "1,2,3"], ["6 comma-separated"]),
        (["--pulses-per-rad", "1,2,3,4,5,x"], ["value 6"]),
        (["--pulses-per-rad", "1,2,3,4,5,-6"], ["positive"]),
    ],
)
def test_bad_options(tmp_path: Path, args: list[str], words: list[str]) -> None:
    traj = write(tmp_path, HEADER6 + "0" + ",0" * 12 + "\n")
    code, _, err = run(str(traj), *args)
    assert code == 2
    for word in words:
        assert word in err


def test_help_says_single_group_only() -> None:
    code, out, _ = run("--help")
    assert code == 0
    flat = " ".join(out.split())  # the help wraps where the terminal width says
    assert "single control group only (not sda10f)" in flat


def test_as_a_process(tmp_path: Path) -> None:
    traj = write(tmp_path, HEADER6 + "0" + ",0" * 12 + "\n0.0085,0.001" + ",0" * 11 + "\n")
    done = subprocess.run(  # noqa: S603 - our own interpreter and module
        [sys.executable, "-m", "pymotoros", "interpolate", str(traj)],
        capture_output=True,
        text=True,
        check=False,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "time_ms,i1,i2,i3,i4,i5,i6"
    assert [line.split(",")[0] for line in done.stdout.splitlines()[1:]] == ["4", "8"]
