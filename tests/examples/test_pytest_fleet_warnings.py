"""The pytest plugin's example (examples/pytest_fleet) runs without a warning, with
pytest-asyncio and without it (issue 28). Its pytest.ini sets
``asyncio_default_fixture_loop_scope``, which pytest-asyncio 0.24 and later ask for (1.x
warns on every run while it is unset, an INTERNALERROR under ``-W error``); where no
loaded pytest-asyncio knows the name (none, or 0.23) the pymotoros plugin declares it, so
pytest does not warn "Unknown config option" either. The plugin picks no scope itself."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "pytest_fleet"
SRC = Path(__file__).resolve().parents[2] / "src"


@pytest.mark.parametrize("asyncio_plugin", ["without", "with"])
def test_the_example_runs_without_warnings(asyncio_plugin: str) -> None:
    pythonpath = os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH")) if p)
    plugin = ["-p", "no:asyncio"] if asyncio_plugin == "without" else []
    done = subprocess.run(  # noqa: S603 - this interpreter running pytest
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-W",
            "error",
            "-p",
            "no:cacheprovider",
            "-p",
            "no:xdist",
            *plugin,
            "-k",
            "test_the_motion_port_answers_a_ping",
        ],
        cwd=EXAMPLE,
        env={**os.environ, "PYTHONPATH": pythonpath},
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
    )
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-3000:]
    assert "1 passed" in output, output[-3000:]
    assert "warning" not in output.lower(), output[-3000:]


def run_pytest(project: Path, *args: str) -> subprocess.CompletedProcess[str]:
    pythonpath = os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH")) if p)
    return subprocess.run(  # noqa: S603 - this interpreter running pytest
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
         *args],
        cwd=project, env={**os.environ, "PYTHONPATH": pythonpath},
        capture_output=True, text=True, check=False, timeout=120,
    )  # fmt: skip


def test_the_plugin_chooses_no_loop_scope_for_the_user(tmp_path: Path) -> None:
    """Where pytest-asyncio 0.24+ is loaded, the plugin leaves the option to it: a project
    that does not set it gets pytest-asyncio's own notice (the plugin does not hide it
    by choosing a scope for the user's async fixtures), and one that sets it gets none."""
    from importlib.metadata import version

    from packaging.version import Version

    (tmp_path / "test_plain.py").write_text("def test_plain():\n    assert True\n")
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    unset = run_pytest(tmp_path)
    assert unset.returncode == 0, unset.stdout[-3000:]
    knows_the_option = Version(version("pytest-asyncio")) >= Version("0.24")
    notice = "asyncio_default_fixture_loop_scope" in unset.stdout + unset.stderr
    assert notice is knows_the_option, unset.stderr[-3000:]
    ini = "[pytest]\nasyncio_default_fixture_loop_scope = function\n"
    (tmp_path / "pytest.ini").write_text(ini)
    for plugin in ([], ["-p", "no:asyncio"]):
        done = run_pytest(tmp_path, "-W", "error", *plugin)
        assert done.returncode == 0, done.stdout[-3000:]
        assert "warning" not in (done.stdout + done.stderr).lower(), done.stdout[-3000:]
