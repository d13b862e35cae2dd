"""Parts are wired at construction (issue 30): no part plugs a hook into another later.

A hook assigned after construction (``fsu.tcp_limiter = lambda ...``,
``controller.drop_motion_hook = ...``, ``server.catch_up = ...``) hides from a reader
what a part can do: its constructor no longer says it, and whoever forgets the line gets
a part that silently does nothing. Every such wire is a constructor argument now (the
ports of ``controller/ports.py``, the runtime's ``ServiceWiring``), and this test keeps
it so: in ``src/`` no attribute of another object is assigned a function, and no
attribute named like a wire is assigned at all.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path
from typing import Final

SRC: Final = Path(__file__).resolve().parents[1] / "src" / "pymotoros"

WIRE_NAMES: Final = re.compile(
    r"(_hook|_hooks|_limiter|_callback|_listener)$|^on_[a-z_]+$"
    r"|^(catch_up|log_clock|recorder|contact|metrics_cell)$"
)
"""Attribute names that wire one part into another (the ones issue 30 found, and their
kind)."""

def _owner(target: ast.Attribute) -> str:
    return ast.unparse(target.value)


def wires(tree: ast.AST) -> list[tuple[int, str]]:
    """``(line, "owner.attr")`` of each attribute of another object assigned a wire:
    a lambda or a function reference, or any value under a wire's name. ``self.x = ``
    is a part's own state; ``self.a.x = `` and ``other.x = `` are another object's."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        else:
            continue
        for target in targets:
            if not isinstance(target, ast.Attribute) or _owner(target) == "self":
                continue
            if isinstance(target.value, ast.Name) and target.value.id in ("past", "member"):
                continue  # a class building its own instance (ServoGroup.past, enum members)
            function_like = isinstance(value, ast.Lambda) or (
                isinstance(value, ast.Attribute)
                and isinstance(value.value, ast.Attribute | ast.Name)
                and not value.attr.isupper()
                and _looks_like_method(value)
            )
            if function_like or WIRE_NAMES.search(target.attr):
                found.append((node.lineno, f"{_owner(target)}.{target.attr}"))
    return found


def _looks_like_method(value: ast.Attribute) -> bool:
    """``self.motion.drop_clients``, ``self.clock.now``: a bound method handed over
    (a verb-ish name on a part); plain data reads (``cell.name``) are not."""
    return value.attr in {
        "drop_clients",
        "now",
        "clip_increment",
        "raise_alarm",
        "servo_off",
        "tick",
        "catch_up",
        "_catch_up",
    }


def test_no_part_is_wired_into_another_after_construction() -> None:
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        rel = str(path.relative_to(SRC))
        for line, what in wires(ast.parse(path.read_text(encoding="utf-8"))):
            offenders.append(f"{rel}:{line}: {what} = ...")
    assert offenders == [], "wire these at construction instead:\n" + "\n".join(offenders)


def test_the_check_finds_the_wires_issue_30_removed() -> None:
    """The old wiring lines, each found (so the test above can fail)."""
    old = """
class VirtualController:
    def __init__(self):
        self._safety.fsu.tcp_limiter = lambda limit, g, cmd, inc: self._tcp.clip(limit)
        self.drop_motion_hook = None

class SimulatorApp:
    def __init__(self, controller):
        for server in (self.motion, self.state, self.io):
            server.catch_up = self._catch_up
            server.log_clock = self.clock.now
        controller.drop_motion_hook = self.motion.drop_clients
        cycle.contact = workspace_contact(ctx)
        servo.recorder = recorder
        app.metrics_cell = cell.name
"""
    assert [what for _, what in sorted(wires(ast.parse(old)))] == [
        "self._safety.fsu.tcp_limiter",
        "server.catch_up",
        "server.log_clock",
        "controller.drop_motion_hook",
        "cycle.contact",
        "servo.recorder",
        "app.metrics_cell",
    ]
