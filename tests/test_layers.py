"""The import rules of docs/architecture.md, checked on the source tree as an allow-list.

Each layer names the parts of the package it *may* import; anything else is a violation,
so a new edge between layers fails here until someone decides it (and updates
docs/architecture.md). The rules are by package prefix, not by module: a new module
inside a layer (``controller/actions.py``, ``models/toml_file.py``) is covered by its
layer's rule without touching this file. A new top-level module belongs to no layer and
fails until it is given one.

Every import counts, including those inside functions (a lazy import is still a
dependency) and relative ones.
"""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Final

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "pymotoros"
PACKAGE: Final = "pymotoros"
ROOT: Final = "pymotoros"
"""The front door (``pymotoros/__init__.py``) as an import target: ``from pymotoros import
__version__``."""

LIBRARY: Final = frozenset(
    {
        "errors",
        "log_tags",
        "protocol",
        "models",
        "motion",
        "kinematics",
        "controller",
        "trajectory",
        "runtime",
        "client",
        "capture",
    }
)
"""Every layer below the top (the CLI, the test twin and the pytest plugin)."""

# layer (module prefix under pymotoros) -> what it may import (prefixes). The longest
# matching prefix decides, so ``protocol.constants`` is stricter than ``protocol``.
ALLOWED: Final[dict[str, frozenset[str]]] = {
    # errors: the exception tree, imported by every layer, importing none
    "errors": frozenset(),
    # log_tags: names of the tags on the client's log records (notes, stop reports) that
    # the CLI prints its own way; a leaf, so the CLI's start-up does not import the client
    "log_tags": frozenset(),
    # protocol: sans-I/O Simple Message codec; constants is its leaf
    "protocol.constants": frozenset({"errors"}),
    "protocol": frozenset({"errors", "protocol"}),
    # models: robot and controller data; the wire's plain data types (constants, and
    # the message records such as DhLink that a model holds) but no framing or sizes
    "models": frozenset({"errors", "models", "protocol.constants", "protocol.messages"}),
    # motion: the bit-faithful interpolator, pure numerics
    "motion": frozenset({"errors", "models", "motion", "protocol.constants"}),
    # kinematics: FK, Jacobian, IK; never motion or controller
    "kinematics": frozenset({"errors", "models", "kinematics", "protocol.constants"}),
    # controller: the virtual controller; never the wire's messages or framing
    "controller": frozenset(
        {"errors", "models", "motion", "kinematics", "controller", "protocol.constants"}
    ),
    # trajectory files, planning and the offline check: on top of models and motion
    "trajectory": frozenset({"errors", "models", "motion", "trajectory", "protocol.constants"}),
    # runtime: the servers, the clock, the HTTP API and the pendant
    "runtime": frozenset(
        {
            "errors",
            "protocol",
            "models",
            "motion",
            "kinematics",
            "controller",
            "capture",
            "runtime",
            ROOT,
        }
    ),
    # client: speaks only the wire (it must work against a real robot)
    "client": frozenset(
        {"errors", "log_tags", "protocol", "models", "kinematics", "capture", "client"}
    ),
    # capture: the pcapng writer of the session recorder, bytes and ports only (dpkt and
    # the standard library), so that both the client and the runtime can use it
    "capture": frozenset(),
    # the CLI: any library layer, never the test twin or the pytest plugin
    "cli": LIBRARY | {"cli", ROOT},
    # the test twin and the pytest plugin sit on top of everything
    "testing": LIBRARY | {"testing"},
    "pytest_plugin": LIBRARY | {"testing"},
    # the front door re-exports from the library layers; ``python -m pymotoros`` runs the CLI
    "__init__": LIBRARY,
    "__main__": frozenset({"cli"}),
}

# Import targets are reduced to these units (longest prefix first), so a rule can allow
# ``protocol.constants`` without ``protocol.framing``.
PROTOCOL_PARTS: Final = ("protocol.constants", "protocol.messages", "protocol.framing")


def _module_name(path: Path) -> str:
    """``controller/safety/fsu.py`` -> ``controller.safety.fsu``; ``__init__.py`` files
    name their package (the front door is ``__init__``)."""
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__" and len(parts) > 1:
        parts.pop()
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Every ``pymotoros`` module ``path`` imports, as a dotted name under the package
    (``protocol.constants``; the front door itself as :data:`ROOT`)."""
    return _imports_in(path.read_text(encoding="utf-8"), path.relative_to(SRC))


def _imports_in(source: str, relative: Path) -> set[str]:
    """:func:`_imports` of ``source``, the module at ``relative`` under the package."""
    tree = ast.parse(source)
    package = list(relative.parent.parts)
    found: set[str] = set()
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against the module's package
                base = package[: len(package) - node.level + 1]
                names = [".".join([PACKAGE, *base, *([node.module] if node.module else [])])]
            elif node.module:
                names = [node.module]
        for name in names:
            if name == PACKAGE:
                found.add(ROOT)
            elif name.startswith(PACKAGE + "."):
                found.add(name.removeprefix(PACKAGE + "."))
    return found


def _within(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def layer_of(module: str) -> str | None:
    """The longest :data:`ALLOWED` key that ``module`` falls under (None: no layer)."""
    keys = [k for k in ALLOWED if _within(module, k)]
    return max(keys, key=len) if keys else None


def allowed(layer: str, target: str) -> bool:
    if target == ROOT:
        return ROOT in ALLOWED[layer]
    return any(_within(target, a) for a in ALLOWED[layer] if a != ROOT)


def _sources() -> list[Path]:
    return sorted(SRC.rglob("*.py"))


def test_every_module_is_in_a_layer() -> None:
    homeless = [
        str(path.relative_to(SRC)) for path in _sources() if layer_of(_module_name(path)) is None
    ]
    assert not homeless, (
        f"{homeless}: in no layer of tests/test_layers.py; give each a layer in ALLOWED "
        "(and in the layer diagram of docs/architecture.md)"
    )


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_layer_imports_only_what_it_may(layer: str) -> None:
    violations = []
    for path in _sources():
        module = _module_name(path)
        if layer_of(module) != layer:
            continue
        for target in sorted(_imports(path)):
            if not allowed(layer, target):
                violations.append(f"{path.relative_to(SRC)} imports pymotoros.{target}")
    assert not violations, (
        f"layer {layer!r} may import only {sorted(ALLOWED[layer])}:\n" + "\n".join(violations)
    )


def test_every_layer_has_modules() -> None:
    layers = {layer_of(_module_name(path)) for path in _sources()}
    assert set(ALLOWED) <= layers, sorted(set(ALLOWED) - layers)


def test_nothing_in_the_package_imports_the_testing_module() -> None:
    importers = [
        str(path.relative_to(SRC))
        for path in _sources()
        if layer_of(_module_name(path)) not in ("testing", "pytest_plugin")
        and any(_within(t, "testing") or _within(t, "pytest_plugin") for t in _imports(path))
    ]
    assert not importers


# ------------------------------------------------------------------ the checker itself


@pytest.mark.parametrize(
    ("layer", "target", "ok"),
    [
        ("protocol", "kinematics", False),  # the gaps of the old list of bans
        ("protocol", "trajectory", False),
        ("protocol", "capture", False),
        ("protocol.constants", "protocol.messages", False),
        ("protocol", "protocol.framing", True),
        ("models", "protocol.constants", True),
        ("models", "protocol.framing", False),
        ("motion", "protocol.messages.trajectory", False),
        ("controller", "controller.actions", True),  # a new module inside a layer
        ("controller", "runtime.ticker", False),
        ("client", "controller", False),
        ("client", "motion", False),
        ("runtime", ROOT, True),
        ("models", ROOT, False),
        ("cli", "testing", False),
    ],
)
def test_the_allow_list_rules(layer: str, target: str, ok: bool) -> None:
    assert allowed(layer, target) is ok


def test_layers_are_found_by_longest_prefix() -> None:
    assert layer_of("protocol.constants") == "protocol.constants"
    assert layer_of("protocol.messages.dh") == "protocol"
    assert layer_of("models.toml_file") == "models"
    assert layer_of("controller.safety.fsu") == "controller"
    assert layer_of("web") is None  # no such layer
    assert layer_of("errors") == "errors"


def test_relative_and_lazy_imports_count() -> None:
    """A relative import resolves against the module's package and an import inside a
    function counts like one at the top."""
    source = "from ..constants import Port\ndef f():\n    from pymotoros.kinematics import x\n"
    found = _imports_in(source, Path("protocol/messages/probe.py"))
    assert found == {"protocol.constants", "kinematics"}
