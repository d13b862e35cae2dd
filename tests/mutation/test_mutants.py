"""The mutation list stays applicable, and the runner never edits the checkout.

The full mutation run (tests/mutation/run.py, from .ci/run) takes minutes; these checks
take a second, so a change that moves a mutated line is noticed in the ordinary suite.
"""

from __future__ import annotations

import importlib.util
import sys
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
