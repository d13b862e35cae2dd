"""The large-file path of ``pymotoros interpolate`` (pyarrow's CSV engine, issue 13) gives
byte-for-byte the output of the Python path, and the same errors."""

from __future__ import annotations

import math
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import pymotoros.cli.interpolate as interpolate_cli
from pymotoros.cli.main import cli

from .test_interpolate import BAD_CSV, HEADER6, test_bad_csv_is_a_clear_error

pytest.importorskip("pyarrow")

ALWAYS: int = 0
NEVER: int = 1 << 62


def trajectory_text(points: int, seed: int) -> str:
    """A smooth 6-axis trajectory with irregular spacing, numbers written at full precision
    (so the parsers' rounding is exercised)."""
    rng = random.Random(seed)
    t = 0.0
    lines = [HEADER6, "0" + ",0" * 12 + "\n"]
    for _ in range(points):
        t += rng.uniform(0.004, 0.1)
        pos = [0.3 * math.sin(t * (1 + 0.2 * i)) * rng.uniform(0.999, 1.0) for i in range(6)]
        lines.append(",".join(repr(x) for x in [t, *pos, *([0.0] * 6)]) + "\n")
    return "".join(lines)


def run(monkeypatch: pytest.MonkeyPatch, threshold: int, *args: str) -> tuple[int, bytes, str]:
    monkeypatch.setattr(interpolate_cli, "FAST_CSV_BYTES", threshold)
    result = CliRunner().invoke(cli, ["interpolate", *args])
    return result.exit_code, result.stdout_bytes, result.stderr


@pytest.mark.parametrize("seed", [1, 2])
def test_fast_and_python_paths_write_the_same_bytes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int
) -> None:
    traj = tmp_path / "traj.csv"
    traj.write_text(trajectory_text(400, seed), encoding="utf-8")
    slow = run(monkeypatch, NEVER, str(traj))
    fast = run(monkeypatch, ALWAYS, str(traj))
    assert slow[0] == fast[0] == 0, (slow[2], fast[2])
    assert len(slow[1].splitlines()) > 400
    assert fast[1] == slow[1]
    out_slow, out_fast = tmp_path / "slow.csv", tmp_path / "fast.csv"
    run(monkeypatch, NEVER, str(traj), "-o", str(out_slow))
    run(monkeypatch, ALWAYS, str(traj), "-o", str(out_fast))
    assert out_fast.read_bytes() == out_slow.read_bytes()


@pytest.mark.parametrize(("text", "words"), BAD_CSV)
def test_the_fast_path_falls_back_for_the_precise_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, words: list[str]
) -> None:
    monkeypatch.setattr(interpolate_cli, "FAST_CSV_BYTES", ALWAYS)
    test_bad_csv_is_a_clear_error(tmp_path, text, words)


@pytest.mark.parametrize("flush", [1, 7, 1 << 16])
def test_block_by_block_writing_gives_the_same_bytes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, flush: int
) -> None:
    """The writer thread takes blocks of any size while the engine computes (its blocks
    made small too, so that there are many)."""
    from pymotoros.motion import batch

    traj = tmp_path / "traj.csv"
    traj.write_text(trajectory_text(300, 3), encoding="utf-8")
    slow = run(monkeypatch, NEVER, str(traj))
    monkeypatch.setattr(interpolate_cli, "FLUSH_ENTRIES", flush)
    monkeypatch.setattr(batch, "SEGMENT_CHUNK", 5)
    fast = run(monkeypatch, ALWAYS, str(traj))
    assert fast[0] == slow[0] == 0
    assert fast[1] == slow[1]
    out = tmp_path / "fast.csv"
    code, _, err = run(monkeypatch, ALWAYS, str(traj), "-o", str(out))
    assert code == 0
    assert out.read_bytes() == slow[1]
    assert f"to {out}" in err


def test_a_refused_trajectory_leaves_no_output_on_the_fast_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    traj = tmp_path / "traj.csv"
    traj.write_text(HEADER6 + "0" + ",0" * 12 + "\n0.1,0.1,0,0,0,0,0,0,0,0,4.0,0,0\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run(monkeypatch, ALWAYS, str(traj), "-o", str(out))
    assert code == 1
    assert "3013" in err
    assert not out.exists()
    code, stdout, err = run(monkeypatch, ALWAYS, str(traj))
    assert code == 1
    assert stdout == b""


def test_timings_are_printed_on_request_only(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    traj = tmp_path / "traj.csv"
    traj.write_text(trajectory_text(20, 4), encoding="utf-8")
    plain = run(monkeypatch, ALWAYS, str(traj))
    assert "timings" not in plain[2]
    monkeypatch.setenv(interpolate_cli.TIMINGS_ENV, "1")
    timed = run(monkeypatch, ALWAYS, str(traj))
    assert timed[1] == plain[1]
    line = timed[2].strip().splitlines()[-1]
    assert line.startswith("interpolate timings monotonic: ")
    marks = dict(item.split("=") for item in line.split(": ", 1)[1].split())
    assert list(marks) == ["start", "read", "check", "engine", "written"]
    values = [float(v) for v in marks.values()]
    assert values == sorted(values)


# Imported by the process below instead of pandas: pyarrow's to_numpy() imports pandas
# when it is installed, which costs ~0.3 s of start-up for nothing.
_NO_PANDAS = "import os, sys\nprint('pandas was imported', file=sys.stderr)\nos._exit(97)\n"
_IMPORTS_TO_AVOID = ("fastapi", "uvicorn", "scipy", "matplotlib", "toppra", "pinocchio")


def test_the_fast_path_imports_neither_pandas_nor_the_heavy_modules(tmp_path: Path) -> None:
    fake = tmp_path / "fake" / "pandas"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text(_NO_PANDAS, encoding="utf-8")
    traj = tmp_path / "traj.csv"
    traj.write_text(trajectory_text(50, 5), encoding="utf-8")
    check = (
        "import sys, runpy\n"
        "import pymotoros.cli.interpolate as m\n"
        "m.FAST_CSV_BYTES = 0\n"
        "sys.argv = ['pymotoros', 'interpolate', sys.argv[1], '-o', sys.argv[2]]\n"
        "try:\n"
        "    runpy.run_module('pymotoros', run_name='__main__')\n"
        "except SystemExit as exc:\n"
        "    assert not exc.code, exc.code\n"
        f"heavy = [m for m in {_IMPORTS_TO_AVOID!r} if m in sys.modules]\n"
        "assert not heavy, heavy\n"
    )
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(
            [str(tmp_path / "fake"), *filter(None, [os.environ.get("PYTHONPATH")])]
        ),
    }
    done = subprocess.run(  # noqa: S603 - our own interpreter
        [sys.executable, "-c", check, str(traj), str(tmp_path / "out.csv")],
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out.csv").read_text(encoding="utf-8").startswith("time_ms,")
