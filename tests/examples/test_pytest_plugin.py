"""The pymotoros pytest plugin, as users run it: examples/pytest_fleet under
``pytest -n 2`` (pytest-xdist), one twin per test on OS-chosen ports (issue 13)."""

from __future__ import annotations

import os
import subprocess
import sys
from importlib.metadata import entry_points
from pathlib import Path

import pytest

pytest.importorskip("xdist")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "pytest_fleet"

RUN_TIMEOUT_S = 300
"""Bound of the whole example run (8 tests, a twin each, two workers)."""


def plugin_args() -> list[str]:
    """Nothing where pymotoros is installed (its ``pytest11`` entry point loads the
    plugin, as for every user, and naming it again would be an error); the explicit
    ``-p`` only for a source tree run against an install made before the entry point
    existed (see tests/conftest.py)."""
    installed = any(ep.value == "pymotoros.pytest_plugin" for ep in entry_points(group="pytest11"))
    if installed and not os.environ.get("PYTEST_DISABLE_PLUGIN_AUTOLOAD"):
        return []
    return ["-p", "pymotoros.pytest_plugin"]


def test_the_example_passes_under_xdist() -> None:
    done = subprocess.run(  # noqa: S603 - this interpreter running pytest
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-n",
            "2",
            "-p",
            "no:cacheprovider",
            "-p",
            "no:benchmark",  # pytest-benchmark (if installed) warns under xdist
            "-W",
            "error",
            *plugin_args(),
        ],
        cwd=EXAMPLE,
        capture_output=True,
        text=True,
        check=False,
        timeout=RUN_TIMEOUT_S,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert "8 passed" in done.stdout


def test_a_failing_test_against_the_twin_fails(tmp_path: Path) -> None:
    """The plugin's fixture really serves: a test expecting a wrong reply fails."""
    (tmp_path / "test_wrong.py").write_text(
        "import socket\n"
        "def test_wrong(pymotoros_twin):\n"
        "    with socket.create_connection(('127.0.0.1', pymotoros_twin.state), timeout=10) as s:\n"
        "        assert s.recv(4096) == b''\n"
    )
    done = subprocess.run(  # noqa: S603 - this interpreter running pytest
        [
            sys.executable,
            *("-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:benchmark"),
            *plugin_args(),
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
        timeout=RUN_TIMEOUT_S,
    )
    assert done.returncode == 1, done.stdout[-3000:]
    assert "1 failed" in done.stdout
