"""The package as an index would get it, installed where nothing else is.

``python -m build`` makes the sdist and the wheel from the files git tracks (copied out,
so the build writes nothing into the checkout), ``twine check --strict`` reads their
metadata as PyPI would (the README renders as the project page), and the wheel,
installed into an empty new virtual environment with its dependencies at the locked
versions (requirements/test.lock as constraints), runs ``pymotoros sim`` on OS-chosen
ports to its ready line, moves the robot with ``pymotoros move`` and stops on SIGTERM.
Nothing comes from the checkout: no PYTHONPATH, a working directory outside it, and
the installed ``pymotoros`` is checked to live in the new environment.

Slow (a build, an install of the runtime dependencies from the package index, a twin's
start-up) but run in CI: each step is bounded.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import tarfile
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "requirements" / "test.lock"

BUILD_TIMEOUT_S = 300
INSTALL_TIMEOUT_S = 600
"""An index download of the runtime dependencies (numpy, scipy, Pinocchio ...), cold."""
READY_TIMEOUT_S = 60
MOVE_TIMEOUT_S = 60

VENV_TIMEOUT_S = 120
STOP_TIMEOUT_S = 30
TEST_TIMEOUT_S = (
    BUILD_TIMEOUT_S + VENV_TIMEOUT_S + INSTALL_TIMEOUT_S + READY_TIMEOUT_S + MOVE_TIMEOUT_S
    + 2 * STOP_TIMEOUT_S
)  # fmt: skip
"""pytest-timeout's bound for one test, fixture setup included (the first test builds
and installs): the sum of the steps' own bounds, so a cold package cache (the install
downloads the runtime dependencies) fails on the step that is slow, naming it, not on
the suite's 120 s default (pyproject.toml)."""

pytestmark = [pytest.mark.slow, pytest.mark.timeout(TEST_TIMEOUT_S)]


def run(argv: list[str], timeout: float, cwd: Path, env: dict[str, str] | None = None) -> str:
    done = subprocess.run(  # noqa: S603 - fixed tools on our own files
        argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout, check=False
    )
    assert done.returncode == 0, f"{argv}: {done.stdout[-3000:]}{done.stderr[-3000:]}"
    return done.stdout


def source_copy(into: Path) -> Path:
    """What the sdist is made of: pyproject.toml, the README and the package sources."""
    tree = into / "pymotoros"
    tree.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, tree / name)
    shutil.copytree(
        ROOT / "src",
        tree / "src",
        ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc"),
    )
    return tree


@pytest.fixture(scope="module")
def dist(tmp_path_factory: pytest.TempPathFactory) -> Path:
    work = tmp_path_factory.mktemp("build")
    out = work / "dist"
    run([sys.executable, "-m", "build", "--outdir", str(out), str(source_copy(work))],
        BUILD_TIMEOUT_S, cwd=work)  # fmt: skip
    return out


@pytest.fixture(scope="module")
def installed(dist: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An empty virtual environment (no pip even) with only the wheel and what it needs."""
    venv = tmp_path_factory.mktemp("venv") / "empty"
    run([sys.executable, "-m", "venv", "--without-pip", str(venv)], VENV_TIMEOUT_S, cwd=venv.parent)
    (wheel,) = dist.glob("pymotoros-*.whl")
    run([sys.executable, "-m", "uv", "pip", "install", "--python", str(venv / "bin" / "python"),
         "--constraint", str(LOCK), str(wheel)], INSTALL_TIMEOUT_S, cwd=venv.parent)  # fmt: skip
    return venv


def clean_env() -> dict[str, str]:
    """This process's environment without anything that would import the checkout."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}


def test_build_makes_an_sdist_and_a_wheel_that_twine_accepts(dist: Path) -> None:
    (sdist,) = dist.glob("pymotoros-*.tar.gz")
    (wheel,) = dist.glob("pymotoros-*-py3-none-any.whl")
    with tarfile.open(sdist) as archive:
        names = archive.getnames()
    assert any(n.endswith("/src/pymotoros/py.typed") for n in names), names[:20]
    wheel_names = zipfile.ZipFile(wheel).namelist()
    assert "pymotoros/py.typed" in wheel_names
    assert any(n.startswith("pymotoros/runtime/pendant/static/") for n in wheel_names)
    output = run([sys.executable, "-m", "twine", "check", "--strict", str(sdist), str(wheel)],
                 120, cwd=dist)  # fmt: skip
    assert output.count("PASSED") == 2, output


@pytest.fixture
def sim(installed: Path, tmp_path: Path) -> Iterator[tuple[Path, dict[str, str]]]:
    """``pymotoros sim`` of the new environment on port 0, up to its ready line."""
    ports_file = tmp_path / "ports.json"
    env = clean_env()
    process = subprocess.Popen(  # noqa: S603 - the installed console script
        [str(installed / "bin" / "pymotoros"), "sim", "--motion-port", "0", "--state-port",
         "0", "--io-port", "0", "--http-port", "0", "--ports-file", str(ports_file)],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert process.stdout is not None
        ready = read_ready_line(process, READY_TIMEOUT_S)
        assert re.fullmatch(r"pymotoros sim ready motion=\d+ state=\d+ io=\d+ http=\d+", ready)
        assert ports_file.exists()
        yield ports_file, env
    finally:
        process.send_signal(signal.SIGTERM)
        try:
            process.communicate(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()
    assert process.returncode == 0, process.returncode
    assert not ports_file.exists()  # removed on exit, as documented


def read_ready_line(process: subprocess.Popen[str], timeout: float) -> str:
    """The first stdout line, or a failure with stderr if the sim ends or takes too long."""
    import selectors

    assert process.stdout is not None
    with selectors.DefaultSelector() as selector:
        selector.register(process.stdout, selectors.EVENT_READ)
        if not selector.select(timeout):
            process.kill()
            _out, err = process.communicate()
            pytest.fail(f"no ready line within {timeout} s: {err[-3000:]}")
    line = process.stdout.readline().strip()
    if not line:
        _out, err = process.communicate(timeout=STOP_TIMEOUT_S)
        pytest.fail(f"pymotoros sim ended without a ready line: {err[-3000:]}")
    return line


def test_the_installed_wheel_runs_the_sim_and_moves_the_robot(
    installed: Path, sim: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    ports_file, env = sim
    python = str(installed / "bin" / "python")
    where = run([python, "-c", "import pymotoros; print(pymotoros.__file__)"], 60, tmp_path, env)
    assert Path(where.strip()).is_relative_to(installed), where  # not the checkout's
    move = [str(installed / "bin" / "pymotoros"), "move", "--enable", "--ports-file",
            str(ports_file), "0.2", "0", "0", "0", "0", "0"]  # fmt: skip
    moved = run(move, MOVE_TIMEOUT_S, tmp_path, env)
    assert re.match(r"reached \[0\.2000, 0\.0000, 0\.0000, 0\.0000, 0\.0000, 0\.0000\] rad", moved)
