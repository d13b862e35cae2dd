"""The mutation list stays applicable, and the runner never edits the checkout.

The full mutation run (tests/mutation/run.py, from .ci/run) takes minutes; these checks
take a second, so a change that moves a mutated line is noticed in the ordinary suite.
"""

from __future__ import annotations

import importlib.util
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

HERE = Path(__file__).resolve().parent
SRC = HERE.parents[1] / "src" / "pymotoros"


def _runner() -> ModuleType:
    spec = importlib.util.spec_from_file_location("mutation_run", HERE / "run.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


RUN = _runner()


@pytest.mark.parametrize("mutant", RUN.MUTANTS, ids=lambda m: m.name)
def test_each_mutant_applies_to_exactly_one_place(mutant: Any) -> None:
    text = (SRC / mutant.path).read_text(encoding="utf-8")
    assert text.count(mutant.old) == 1, (
        f"{mutant.name}: its text is no longer found exactly once in "
        f"{mutant.path}; update MUTANTS in tests/mutation/run.py"
    )
    assert mutant.old != mutant.new
    for test in mutant.tests:
        if test.endswith(".py"):
            assert (HERE.parents[1] / test).is_file(), test


def test_names_are_unique() -> None:
    names = [m.name for m in RUN.MUTANTS]
    assert len(names) == len(set(names))


def test_a_mutant_is_applied_to_the_copy_only_and_undone(tmp_path: Path) -> None:
    mutant = RUN.MUTANTS[0]
    original = (SRC / mutant.path).read_text(encoding="utf-8")
    src = RUN._copy_source(tmp_path)
    copied = src / "pymotoros" / mutant.path
    # a test selection that cannot run: the mutant is applied, the run errors, and
    # both the copy and the checkout end as they began
    broken = RUN.Mutant(
        mutant.name, mutant.rule, mutant.path, mutant.old, mutant.new, ("no_such_test.py",)
    )
    result = RUN.run_one(src, broken)
    assert result.outcome == "error"
    assert copied.read_text(encoding="utf-8") == original
    assert (SRC / mutant.path).read_text(encoding="utf-8") == original


def test_stale_text_is_reported_not_skipped(tmp_path: Path) -> None:
    src = RUN._copy_source(tmp_path)
    gone = RUN.Mutant("gone", "a rule", "models/rules.py", "no such text anywhere", "x", ())
    result = RUN.run_one(src, gone)
    assert result.outcome == "stale"
    assert "not found" in result.detail


def _children(pid: int) -> list[int]:
    """Process ids whose parent is ``pid`` (Linux /proc)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="Linux /proc")
def test_an_interrupted_run_ends_its_tests_and_removes_its_copies(tmp_path: Path) -> None:
    """SIGTERM (a CI timeout) in the middle of a mutant's test run: the runner ends its
    pytest child, removes its temporary copies and leaves the checkout as it was."""
    mutant = RUN.MUTANTS[0]
    original = (SRC / mutant.path).read_text(encoding="utf-8")
    env = dict(os.environ, TMPDIR=str(tmp_path))
    runner = subprocess.Popen(  # noqa: S603 - this interpreter, fixed arguments
        [sys.executable, str(HERE / "run.py"), "--no-baseline", "--only", mutant.name],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        child: list[int] = []
        for _ in range(1200):  # bounded: up to a minute for the first pytest to start
            child = [pid for pid in _children(runner.pid) if b"pytest" in _cmdline(pid)]
            if child or runner.poll() is not None:
                break
            time.sleep(0.05)
        assert child, "the runner never started a test run"
        runner.send_signal(signal.SIGTERM)
        runner.wait(timeout=60)
    finally:
        if runner.poll() is None:
            runner.kill()
            runner.wait()
    assert runner.returncode != 0
    for pid in child:
        assert not Path(f"/proc/{pid}").exists() or "Z" in _state(pid), f"pytest {pid} left"
    assert not list(tmp_path.glob("pymotoros-mutation-*"))
    assert (SRC / mutant.path).read_text(encoding="utf-8") == original


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "gone"


def _cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""
