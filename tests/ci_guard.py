"""Two guards for the test run, loaded by tests/conftest.py.

1. **In CI no test skips.** A test that needs a real component (tshark, Chromium and
   chromedriver, selenium, pyarrow, Linux's timerfd …) skips on a developer's machine
   that lacks it, saying why; in CI (``CI`` set to ``true``/``1``/``yes``, as GitHub
   Actions, GitLab and ``.ci/run`` set it) such a skip would leave the component
   untested while the run stays green, so there it becomes a failure that names the
   reason. ``.ci/run`` installs every component first and stops, naming the package,
   when one cannot be installed.
2. **Tests write only into temporary directories.** The run records ``git status`` of
   the source tree before and after; a file the run created or changed (a tracked
   screenshot overwritten, a stray output file) fails the run in CI and is reported as
   a warning elsewhere (a developer may be editing files while the tests run).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest

GIT_TIMEOUT_S = 30.0
_BEFORE = pytest.StashKey[frozenset[str] | None]()


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def _ci_failure(reason: str) -> str:
    return (
        f"skipped in CI: {reason}\n"
        "In CI every test runs (CI is set): install what it needs (.ci/run does, and stops "
        "naming the package it could not install), or run outside CI to let it skip."
    )


def _skip_reason(longrepr: Any) -> str:
    if isinstance(longrepr, tuple) and len(longrepr) == 3:
        return str(longrepr[2]).removeprefix("Skipped: ")
    return str(longrepr)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, Any, None]:
    outcome = yield
    report = outcome.get_result()
    if in_ci() and report.skipped and not hasattr(report, "wasxfail"):
        report.outcome = "failed"
        report.longrepr = _ci_failure(_skip_reason(report.longrepr))


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector: pytest.Collector) -> Generator[None, Any, None]:
    """A module skipped at import (``pytest.importorskip``) is a collection error in CI."""
    outcome = yield
    report = outcome.get_result()
    if in_ci() and report.skipped:
        report.outcome = "failed"
        report.longrepr = _ci_failure(_skip_reason(report.longrepr))


def _git_status(root: Path) -> frozenset[str] | None:
    """``git status --porcelain`` lines of the run's root directory (the checkout); None
    without git or outside a checkout."""
    git = shutil.which("git")
    if git is None or not (root / ".git").exists():
        return None
    done = subprocess.run(  # noqa: S603 - git found on PATH, fixed arguments
        [git, "-C", str(root), "status", "--porcelain", "--untracked-files=all"],
        capture_output=True,
        text=True,
        timeout=GIT_TIMEOUT_S,
        check=False,
    )
    if done.returncode != 0:
        return None
    return frozenset(done.stdout.splitlines())


def _is_worker(config: pytest.Config) -> bool:
    return hasattr(config, "workerinput")  # an xdist worker: the controller checks


def pytest_sessionstart(session: pytest.Session) -> None:
    if not _is_worker(session.config):
        session.config.stash[_BEFORE] = _git_status(session.config.rootpath)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    config = session.config
    if _is_worker(config):
        return
    before = config.stash.get(_BEFORE, None)
    after = _git_status(config.rootpath) if before is not None else None
    if before is None or after is None:
        return
    changed = sorted(after - before)
    if not changed:
        return
    lines = "\n".join(f"  {line}" for line in changed)
    text = (
        "the test run changed the source tree (tests must write only into temporary "
        f"directories, e.g. tmp_path):\n{lines}"
    )
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line(("ERROR: " if in_ci() else "WARNING: ") + text, red=True)
    if in_ci() and session.exitstatus == 0:
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
