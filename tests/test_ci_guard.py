"""tests/ci_guard.py: in CI a skip fails, and a run that changes the checkout is caught.

Each case runs pytest in a subprocess on a small test file in a temporary directory, with
the guard loaded as a plugin (``-p ci_guard``), as tests/conftest.py loads it here.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
RUN_TIMEOUT_S = 120.0

SKIPS = """
import pytest

def test_needs_a_tool():
    pytest.skip("frobnicator is not installed (apt-get install frobnicator)")

def test_runs():
    assert True
"""

IMPORT_SKIP = """
import pytest
pytest.importorskip("no_such_module_for_the_guard", reason="no_such_module is not installed")

def test_never_runs():
    assert True
"""

WRITES = """
from pathlib import Path

def test_writes_into_the_checkout():
    (Path(__file__).parent / "stray.txt").write_text("oops")
"""


def _run(tmp_path: Path, source: str, *, ci: bool) -> subprocess.CompletedProcess[str]:
    (tmp_path / "test_probe.py").write_text(source, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    if ci:
        env["CI"] = "true"
    env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"  # only the guard: a fast start
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "ci_guard", "-p", "no:cacheprovider", "-rA"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )


def test_in_ci_a_skip_is_a_failure_naming_the_reason(tmp_path: Path) -> None:
    done = _run(tmp_path, SKIPS, ci=True)
    assert done.returncode == pytest.ExitCode.TESTS_FAILED, done.stdout
    assert "skipped in CI: frobnicator is not installed" in done.stdout
    assert "1 failed, 1 passed" in done.stdout


def test_outside_ci_a_skip_stays_a_skip(tmp_path: Path) -> None:
    done = _run(tmp_path, SKIPS, ci=False)
    assert done.returncode == pytest.ExitCode.OK, done.stdout
    assert "1 passed, 1 skipped" in done.stdout


def test_in_ci_a_module_skipped_at_import_is_an_error(tmp_path: Path) -> None:
    done = _run(tmp_path, IMPORT_SKIP, ci=True)
    assert done.returncode != pytest.ExitCode.OK, done.stdout
    assert "skipped in CI: no_such_module is not installed" in done.stdout


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
@pytest.mark.parametrize("ci", [True, False])
def test_a_run_that_changes_the_checkout_is_caught(tmp_path: Path, ci: bool) -> None:
    git = shutil.which("git")
    assert git is not None
    subprocess.run([git, "init", "-q", str(tmp_path)], check=True, timeout=RUN_TIMEOUT_S)  # noqa: S603
    done = _run(tmp_path, WRITES, ci=ci)
    assert "the test run changed the source tree" in done.stdout
    assert "?? stray.txt" in done.stdout
    if ci:
        assert done.returncode == pytest.ExitCode.TESTS_FAILED, done.stdout
    else:
        assert done.returncode == pytest.ExitCode.OK, done.stdout
