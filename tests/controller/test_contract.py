"""The controller's contract is a leaf: its values import nothing else of the controller,
and the protocols over them need no deferred or ``TYPE_CHECKING`` import (issue 30)."""

from __future__ import annotations

import ast
import dataclasses
import typing
from pathlib import Path

import pymotoros.controller.actions as actions_module
from pymotoros.controller import values
from pymotoros.controller.values import ControllerSnapshot

CONTROLLER = Path(values.__file__).resolve().parent


def _imports(path: Path) -> list[tuple[str, bool]]:
    """(module, at the top level) of every ``import``/``from`` in a file."""
    tree = ast.parse(path.read_text())
    top = {id(node) for node in tree.body}
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            out.append((node.module, id(node) in top))
        elif isinstance(node, ast.Import):
            out += [(alias.name, id(node) in top) for alias in node.names]
    return out


def test_the_values_import_nothing_else_of_the_controller() -> None:
    inside = [
        m for m, _ in _imports(CONTROLLER / "values.py") if m.startswith("pymotoros.controller")
    ]
    assert inside == []


def test_the_protocols_and_the_cycle_breakers_import_at_the_top_only() -> None:
    """No import inside a function or under ``if TYPE_CHECKING``: every dependency is one a
    reader and the import graph see."""
    for name in ("api.py", "values.py", "actions.py", "scenario.py", "cell.py", "alarms.py"):
        source = (CONTROLLER / name).read_text()
        assert "TYPE_CHECKING" not in source, name
        deferred = [m for m, top in _imports(CONTROLLER / name) if not top]
        assert deferred == [], name


def test_the_actions_do_not_import_scenario_loading() -> None:
    modules = [m for m, _ in _imports(Path(actions_module.__file__))]
    assert "pymotoros.controller.scenario" not in modules


def test_every_snapshot_type_hint_resolves_without_a_local_namespace() -> None:
    hints = typing.get_type_hints(ControllerSnapshot)
    assert {f.name for f in dataclasses.fields(ControllerSnapshot)} <= set(hints)


def test_the_compatibility_aliases_are_gone() -> None:
    import pymotoros.controller.api as api
    import pymotoros.controller.scenario as scenario

    assert not hasattr(scenario, "ScenarioTarget")
    assert not hasattr(api, "PendantMode")
    assert not hasattr(ControllerSnapshot, "fsu_joint_speed_pct")
    assert not hasattr(ControllerSnapshot, "fsu_tcp_speed_mm_s")
