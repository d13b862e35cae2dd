""".ci/run stops, naming the package, when a component the tests need is missing.

The script is run with a PATH holding only the few commands it needs to get that far
(no apt-get, so nothing is installed, and none of tshark, chromium, chromedriver, git):
it must fail before installing anything, naming each Debian package.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RUN_TIMEOUT_S = 60.0


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_a_missing_component_fails_the_run_naming_its_package(tmp_path: Path) -> None:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in ("dirname", "cat"):
        found = shutil.which(tool)
        assert found is not None, tool
        (bin_dir / tool).symlink_to(found)
    bash = shutil.which("bash")
    assert bash is not None
    done = subprocess.run(  # noqa: S603 - bash found on PATH, fixed arguments
        [bash, str(ROOT / ".ci" / "run")],
        env={"PATH": str(bin_dir), "HOME": str(tmp_path)},
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )
    assert done.returncode == 1, done.stderr
    for command, package in (
        ("tshark", "tshark"),
        ("chromium", "chromium"),
        ("chromedriver", "chromium-driver"),
        ("git", "git"),
    ):
        assert f"'{command}' is missing: install the Debian package '{package}'" in done.stderr
    assert "pip" not in done.stdout  # stopped before installing or testing anything
