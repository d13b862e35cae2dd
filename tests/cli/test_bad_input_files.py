"""No traceback for a bad input (issue 20, item 6): every file-reading command turns a
bad file into one line and exit code 2.

A Hypothesis test corrupts good files in one way each (a cell that is not a finite
number, a short or long row, bytes that are not UTF-8, an empty file, a missing file)
and throws them at ``plan``, ``check``, ``run`` (its offline part: the file is read
before any connection), ``plot``, ``interpolate`` and ``replay``, in process through
click's CliRunner."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pymotoros.cli.main import cli

EXIT_USAGE = 2

WAYPOINTS = "s,l,u,r,b,t\n0,0,0,0,0,0\n0.4,0.2,0.3,0,-0.5,0\n0,0,0,0,0,0\n"
TRAJ_CSV = (
    "time,p1,p2,p3,p4,p5,p6,v1,v2,v3,v4,v5,v6\n"
    "0,0,0,0,0,0,0,0,0,0,0,0,0\n"
    "0.5,0.01,0,0,0,0,0,0,0,0,0,0,0\n"
    "1.0,0.02,0,0,0,0,0,0,0,0,0,0,0\n"
)
NOT_FINITE = ["nan", "NaN", "inf", "-inf", "Infinity", "1e999", "abc", "", "0x1", "1,5"]
NOWHERE = ["--motion-port", "1", "--state-port", "1", "--io-port", "1", "--timeout", "0.2"]


def _short_error(result: Result) -> str:
    """Exit 2, no traceback, the error on one line."""
    assert result.exit_code == EXIT_USAGE, (result.exit_code, result.output, result.exception)
    assert "Traceback" not in result.output
    assert not isinstance(result.exception, Exception) or isinstance(
        result.exception, SystemExit
    ), repr(result.exception)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert len(lines[0]) < 400, lines[0]
    return lines[0]


@st.composite
def corrupted(draw: st.DrawFn, good: str) -> bytes:
    """``good`` (a CSV with a header row) broken in one way that no reader may accept."""
    rows = [r.split(",") for r in good.strip().splitlines()]
    how = draw(st.sampled_from(["cell", "short", "long", "bytes", "empty"]))
    if how == "bytes":
        junk = draw(st.binary(min_size=1, max_size=20).filter(_not_utf8))
        return good.encode()[: draw(st.integers(0, len(good)))] + junk
    if how == "empty":
        return b""
    r = draw(st.integers(1, len(rows) - 1))  # a data row: the header may hold text
    row = rows[r]
    if how == "cell":
        row[draw(st.integers(0, len(row) - 1))] = draw(st.sampled_from(NOT_FINITE))
    elif how == "short":
        del row[draw(st.integers(1, len(row) - 1)) :]
    else:
        row.extend(draw(st.lists(st.sampled_from(["0", "1.5", "-2"]), min_size=1, max_size=3)))
    return ("\n".join(",".join(x) for x in rows) + "\n").encode()


BAD_VALUES: list[Any] = [
    float("nan"),
    float("inf"),
    -float("inf"),
    10**400,
    "x",
    None,
    [],
    True,
    {"secs": 10**400},
]


@st.composite
def corrupted_json(draw: st.DrawFn) -> bytes:
    """A good pymotoros JSON trajectory with one value made unusable, or a list cut."""
    names = ["joint_1_s", "joint_2_l", "joint_3_u", "joint_4_r", "joint_5_b", "joint_6_t"]
    points = [
        {"time": t, "positions": [0.01 * t] + [0.0] * 5, "velocities": [0.0] * 6}
        for t in (0.0, 0.5, 1.0)
    ]
    doc = {"format": "pymotoros-trajectory", "version": 1, "joint_names": names}
    point = draw(st.sampled_from(points))
    key = draw(st.sampled_from(["time", "positions", "velocities", "cut"]))
    bad = draw(st.sampled_from(BAD_VALUES))
    if key == "time":
        point["time"] = bad if not isinstance(bad, bool) else "true"
    elif key == "cut":
        point["positions"] = point["positions"][: draw(st.integers(0, 5))]
    else:
        point[key][draw(st.integers(0, 5))] = bad
    doc["points"] = points
    return json.dumps(doc).encode()


def _not_utf8(data: bytes) -> bool:
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return True
    return False


def _invoke(tmp: Path, name: str, content: bytes | None, args: list[str]) -> Result:
    path = tmp / name
    if content is not None:
        path.write_bytes(content)
    return CliRunner().invoke(cli, [a.replace("{file}", str(path)) for a in args])


FAST = settings(
    max_examples=15,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@FAST
@given(content=corrupted(WAYPOINTS))
def test_plan_refuses_bad_waypoints_in_one_line(content: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "out.yaml")
        _short_error(_invoke(Path(tmp), "way.csv", content, ["plan", "{file}", "-o", out]))


@FAST
@given(
    content=corrupted(TRAJ_CSV),
    command=st.sampled_from(
        [
            ["check", "{file}"],
            ["run", "{file}", *NOWHERE],
            ["plot", "{file}", "-o", "{file}.png"],
            ["interpolate", "{file}"],
        ]
    ),
)
def test_trajectory_commands_refuse_bad_files_in_one_line(
    content: bytes, command: list[str]
) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        _short_error(_invoke(Path(tmp), "traj.csv", content, command))


@FAST
@given(
    content=corrupted_json(),
    command=st.sampled_from([["check", "{file}"], ["run", "{file}", *NOWHERE]]),
)
def test_a_bad_json_trajectory_is_one_line(content: bytes, command: list[str]) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        _short_error(_invoke(Path(tmp), "traj.json", content, command))


@FAST
@given(content=st.binary(max_size=64))
def test_replay_refuses_a_file_that_is_no_recording(content: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        _short_error(_invoke(Path(tmp), "rec.pcapng", content, ["replay", "{file}"]))


@pytest.mark.parametrize(
    "command",
    [
        ["plan", "{file}", "-o", "out.yaml"],
        ["check", "{file}"],
        ["run", "{file}", *NOWHERE],
        ["plot", "{file}", "-o", "out.png"],
        ["interpolate", "{file}"],
        ["replay", "{file}"],
    ],
)
def test_a_missing_file_is_one_line(tmp_path: Path, command: list[str]) -> None:
    line = _short_error(_invoke(tmp_path, "missing.csv", None, command))
    assert "no such file" in line


@pytest.mark.parametrize(
    ("name", "content", "command"),
    [
        ("way.csv", WAYPOINTS, ["plan", "{file}", "-o", "{dir}/out.yaml"]),
        ("traj.csv", TRAJ_CSV, ["plot", "{file}", "-o", "{dir}/out.png"]),
        ("traj.csv", TRAJ_CSV, ["interpolate", "{file}", "-o", "{dir}/out.csv"]),
        (None, "", ["urdf", "-o", "{dir}/hc10.urdf"]),
    ],
    ids=["plan", "plot", "interpolate", "urdf"],
)
def test_output_into_a_missing_directory_is_one_line(
    tmp_path: Path, name: str | None, content: str, command: list[str]
) -> None:
    missing = tmp_path / "no" / "such"
    args = [a.replace("{dir}", str(missing)) for a in command]
    if name is None:
        result = CliRunner().invoke(cli, args)
    else:
        result = _invoke(tmp_path, name, content.encode(), args)
    line = _short_error(result)
    assert f"the directory {missing} does not exist" in line
    assert "mkdir -p" in line
    assert not missing.exists()


def test_plan_with_a_nan_waypoint_names_the_line(tmp_path: Path) -> None:
    way = tmp_path / "way.csv"
    way.write_text("s,l,u,r,b,t\n0,0,0,0,0,0\n0.4,nan,0.3,0,-0.5,0\n")
    line = _short_error(CliRunner().invoke(cli, ["plan", str(way), "-o", str(tmp_path / "o.csv")]))
    assert "line 3" in line
    assert "not a finite number" in line


def test_plan_with_a_short_row_says_how_many_values(tmp_path: Path) -> None:
    way = tmp_path / "way.csv"
    way.write_text("s,l,u,r,b,t\n0,0,0,0,0,0\n0.4,0.2\n")
    line = _short_error(CliRunner().invoke(cli, ["plan", str(way), "-o", str(tmp_path / "o.csv")]))
    assert "line 3: 2 values, the robot has 6 joints" in line


def test_plot_with_an_unknown_image_suffix_is_one_line(tmp_path: Path) -> None:
    traj = tmp_path / "t.csv"
    traj.write_text(TRAJ_CSV)
    line = _short_error(CliRunner().invoke(cli, ["plot", str(traj), "-o", str(tmp_path / "x.q")]))
    assert ".png" in line
