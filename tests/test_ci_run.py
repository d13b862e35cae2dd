""".ci/run, run for real with stand-ins for the commands it calls.

- It stops, naming the package, when a component the tests need is missing: run with a
  PATH holding only the few commands it needs to get that far (no apt-get, so nothing is
  installed, and none of tshark, chromium, chromedriver, git), it must fail before
  installing anything, naming each Debian package.
- Installing the missing packages needs root: a user with passwordless sudo installs
  through ``sudo -n``; one without is told so (and the packages are still named).
- It creates a fresh virtual environment outside the checkout, installs the lock into
  it, runs the README's test command, ruff, mypy and the mutation run with that
  environment's python, in that order, stops at the first failure, and removes the
  environment afterwards. A stand-in ``python3`` records every call (and makes the
  environment's ``python``, the same stand-in).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RUN_TIMEOUT_S = 60.0


def bin_with(tmp_path: Path, tools: tuple[str, ...]) -> Path:
    """A fresh ``bin`` directory under ``tmp_path`` holding links to just ``tools``."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in tools:
        found = shutil.which(tool)
        assert found is not None, tool
        (bin_dir / tool).symlink_to(found)
    return bin_dir


def run_ci(env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """``.ci/run`` under bash with only ``env`` as its environment."""
    bash = shutil.which("bash")
    assert bash is not None
    return subprocess.run(  # noqa: S603 - bash found on PATH, fixed arguments
        [bash, str(ROOT / ".ci" / "run")],
        env=env,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_a_missing_component_fails_the_run_naming_its_package(tmp_path: Path) -> None:
    bin_dir = bin_with(tmp_path, ("dirname", "cat"))
    done = run_ci({"PATH": str(bin_dir), "HOME": str(tmp_path)})
    assert done.returncode == 1, done.stderr
    for command, package in (
        ("tshark", "tshark"),
        ("chromium", "chromium"),
        ("chromedriver", "chromium-driver"),
        ("git", "git"),
    ):
        assert f"'{command}' is missing: install the Debian package '{package}'" in done.stderr
    assert "pip" not in done.stdout  # stopped before installing or testing anything


STAND_IN_PYTHON = """#!/bin/bash
# records its arguments; `-m venv DIR` makes DIR/bin/python (this same script)
echo "$0 $*" >> "$CI_LOG"
if [ "$1" = -m ] && [ "$2" = venv ]; then
    mkdir -p "$3/bin" && cp "$0" "$3/bin/python"
fi
if [ "$*" = "-m pytest" ]; then
    exit "${PYTEST_EXIT:-0}"
fi
exit 0
"""


def run_with_stand_ins(tmp_path: Path, pytest_exit: int = 0) -> tuple[int, list[str], Path]:
    bin_dir = bin_with(tmp_path, ("dirname", "cat", "mktemp", "rm", "mkdir", "cp"))
    for present in ("tshark", "chromium", "chromedriver", "git"):  # nothing to apt-get
        (bin_dir / present).write_text("#!/bin/sh\nexit 0\n")
        (bin_dir / present).chmod(0o755)
    (bin_dir / "python3").write_text(STAND_IN_PYTHON)
    (bin_dir / "python3").chmod(0o755)
    temp = tmp_path / "temp"
    temp.mkdir()
    log = tmp_path / "calls.log"
    done = run_ci(
        {
            "PATH": str(bin_dir),
            "HOME": str(tmp_path),
            "TMPDIR": str(temp),
            "CI_LOG": str(log),
            "PYTEST_EXIT": str(pytest_exit),
        }
    )
    calls = log.read_text().splitlines() if log.exists() else []
    return done.returncode, calls, temp


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_it_installs_the_lock_into_a_fresh_venv_and_runs_everything_there(
    tmp_path: Path,
) -> None:
    returncode, calls, temp = run_with_stand_ins(tmp_path)
    assert returncode == 0, calls
    creator, venv = calls[0].split(" -m venv ")
    assert creator == str(tmp_path / "bin" / "python3")
    assert Path(venv).parent.parent == temp, venv  # a new directory, outside the checkout
    python = f"{venv}/bin/python"
    assert calls[1:] == [
        f"{python} -m pip install -r requirements/test.lock",
        f"{python} -m pip install -e .[test]",  # the README's command, unchanged
        f"{python} -m pytest",
        f"{python} -m ruff check .",
        f"{python} -m mypy",
        f"{python} tests/mutation/run.py --no-baseline",
    ]
    assert list(temp.iterdir()) == []  # the environment is removed afterwards


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
@pytest.mark.parametrize("pytest_exit", [1, 5])  # 5: pytest collected no test
def test_a_failing_test_run_stops_it(tmp_path: Path, pytest_exit: int) -> None:
    returncode, calls, _temp = run_with_stand_ins(tmp_path, pytest_exit)
    assert returncode == pytest_exit
    assert calls[-1].endswith(" -m pytest"), calls  # neither ruff nor mypy nor mutants ran


def run_as_user(tmp_path: Path, *, sudo: bool) -> tuple[subprocess.CompletedProcess[str], str]:
    """.ci/run as uid 1000 with a stand-in apt-get (installs nothing, records its calls)
    and, if ``sudo``, a passwordless stand-in sudo that runs what it is given."""
    bin_dir = bin_with(tmp_path, ("dirname", "cat", "env"))
    log = tmp_path / "calls.log"
    stand_ins = {
        "id": "#!/bin/bash\necho 1000\n",
        "apt-get": f'#!/bin/bash\necho "apt-get $*" >> {log}\n',
        "debconf-set-selections": "#!/bin/bash\ncat >/dev/null\n",
    }
    if sudo:
        stand_ins["sudo"] = f'#!/bin/bash\necho "sudo $*" >> {log}\n[ "$1" = -n ] && shift\n"$@"\n'
    for name, text in stand_ins.items():
        (bin_dir / name).write_text(text)
        (bin_dir / name).chmod(0o755)
    done = run_ci({"PATH": str(bin_dir), "HOME": str(tmp_path)})
    return done, log.read_text() if log.exists() else ""


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_a_user_with_sudo_installs_through_sudo(tmp_path: Path) -> None:
    done, calls = run_as_user(tmp_path, sudo=True)
    assert "sudo -n apt-get update" in calls, (calls, done.stderr)
    assert "sudo -n env DEBIAN_FRONTEND=noninteractive apt-get install -y tshark" in calls
    assert "apt-get install -y chromium-driver" in calls
    assert done.returncode == 1  # the stand-in installed nothing: still named
    assert "'tshark' is missing" in done.stderr


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_a_user_without_sudo_is_told_root_is_needed(tmp_path: Path) -> None:
    done, calls = run_as_user(tmp_path, sudo=False)
    assert calls == ""  # apt-get never tried
    assert "needs root: run as root or with passwordless sudo" in done.stderr
    assert "install the Debian package 'chromium-driver'" in done.stderr
    assert done.returncode == 1
