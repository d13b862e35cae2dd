"""The pytest plugin's example (examples/pytest_fleet) runs without a warning for a user
who has not installed pytest-asyncio: its pytest.ini names no option that only
pytest-asyncio knows ("Unknown config option: asyncio_default_fixture_loop_scope")."""

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
