"""The import rules of docs/architecture.md, checked on the source tree as an allow-list.

Each layer names the parts of the package it *may* import; anything else is a violation,
so a new edge between layers fails here until someone decides it (and updates
docs/architecture.md). The rules are by package prefix, not by module: a new module
inside a layer (``controller/actions.py``, ``models/toml_file.py``) is covered by its
layer's rule without touching this file. A new top-level module belongs to no layer and
fails until it is given one.

Every import counts, including those inside functions (a lazy import is still a
dependency), those under ``if TYPE_CHECKING:`` (the type checker follows them) and
relative ones.

Inside the package, module by module: no import cycle (two modules that import each
other, at the top, in a function or for the type checker, are one unit that cannot be
read, tested or moved apart), and no private name (``_x``) imported from another module
(a private module, ``_base``, only from inside its own package). A failure names the
modules of the cycle, or the importer, the module and the name.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import dataclass
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
    function, or under ``if TYPE_CHECKING:``, counts like one at the top."""
    source = (
        "from typing import TYPE_CHECKING\n"
        "from ..constants import Port\n"
        "if TYPE_CHECKING:\n    from pymotoros.runtime.app import SimulatorApp\n"
        "def f():\n    from pymotoros.kinematics import x\n"
    )
    found = _imports_in(source, Path("protocol/messages/probe.py"))
    assert found == {"protocol.constants", "kinematics", "runtime.app"}
    assert not allowed("protocol", "runtime.app")  # so the layer test above fails on it


# ------------------------------------------------------------------ the module graph


@dataclass(frozen=True, slots=True)
class ImportEdge:
    """``importer`` imports ``target`` (both dotted module names) at ``line``, ``how``."""

    importer: str
    target: str
    line: int
    how: str
    """``at the top``, ``in a function`` or ``under TYPE_CHECKING``."""

    def __str__(self) -> str:
        return f"{self.importer} -> {self.target} (line {self.line}, {self.how})"


@dataclass(frozen=True, slots=True)
class PrivateImport:
    importer: str
    module: str
    name: str
    line: int

    def __str__(self) -> str:
        return f"{self.importer} imports {self.name} from {self.module} (line {self.line})"


def modules_under(src: Path) -> dict[str, Path]:
    """Every module of the package under ``src`` by dotted name (a package by its own
    name: ``pymotoros.controller`` is ``controller/__init__.py``)."""
    found: dict[str, Path] = {}
    for path in sorted((src / PACKAGE).rglob("*.py")):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


class _ImportVisitor(ast.NodeVisitor):
    """Each import statement of a module with where it sits (top, function, TYPE_CHECKING)."""

    def __init__(self) -> None:
        self.found: list[tuple[ast.Import | ast.ImportFrom, str]] = []
        self._where: list[str] = []

    def _nested(self, node: ast.AST, how: str) -> None:
        self._where.append(how)
        self.generic_visit(node)
        self._where.pop()

    def visit_FunctionDef(self, node: ast.FunctionDef) -> None:
        self._nested(node, "in a function")

    def visit_AsyncFunctionDef(self, node: ast.AsyncFunctionDef) -> None:
        self._nested(node, "in a function")

    def visit_If(self, node: ast.If) -> None:
        test = ast.unparse(node.test)
        if test in ("TYPE_CHECKING", "typing.TYPE_CHECKING"):
            self._where.append("under TYPE_CHECKING")
            for child in node.body:
                self.visit(child)
            self._where.pop()
            for child in node.orelse:
                self.visit(child)
        else:
            self.generic_visit(node)

    def visit_Import(self, node: ast.Import) -> None:
        self.found.append((node, self._how()))

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        self.found.append((node, self._how()))

    def _how(self) -> str:
        if "under TYPE_CHECKING" in self._where:
            return "under TYPE_CHECKING"
        return self._where[-1] if self._where else "at the top"


def _owner(name: str, modules: dict[str, Path]) -> str | None:
    """The module ``name`` is in: itself, else its longest prefix that is a module."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _is_private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def package_imports(src: Path) -> tuple[list[ImportEdge], list[PrivateImport]]:
    """Every import between the package's modules under ``src`` (in functions and under
    ``TYPE_CHECKING`` too), and every private name or module imported from elsewhere.

    ``from pymotoros.a import b`` imports the module ``pymotoros.a.b`` when there is one,
    else a name of ``pymotoros.a``; importing ``pymotoros.a.b`` also runs
    ``pymotoros.a/__init__.py``, but that implicit parent import is not an edge (every
    package's modules would otherwise form a cycle with a package that imports them).
    """
    modules = modules_under(src)
    edges: list[ImportEdge] = []
    private: list[PrivateImport] = []
    for module, path in modules.items():
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        visitor = _ImportVisitor()
        visitor.visit(ast.parse(path.read_text(encoding="utf-8")))
        for node, how in visitor.found:
            targets: list[tuple[str, str | None]] = []  # (module, name imported from it)
            if isinstance(node, ast.Import):
                targets = [(alias.name, None) for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    parts = package.split(".")
                    parts = parts[: len(parts) - node.level + 1]
                    base = ".".join([*parts, *([base] if base else [])])
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    targets.append((full, None) if full in modules else (base, alias.name))
            for name, imported in targets:
                target = _owner(name, modules) if _within(name, PACKAGE) else None
                if target is None:
                    continue
                if target != module:
                    edges.append(ImportEdge(module, target, node.lineno, how))
                if imported is not None and _is_private(imported):
                    private.append(PrivateImport(module, target, imported, node.lineno))
                hidden = _private_package(target)
                if hidden is not None and not _within(module, hidden):
                    private.append(
                        PrivateImport(
                            module, hidden, target.removeprefix(hidden + "."), node.lineno
                        )
                    )
    return edges, private


def _private_package(module: str) -> str | None:
    """The package a private module (``pymotoros.protocol.messages._base``) belongs to,
    whose modules alone may import it (None: no part of the name is private)."""
    parts = module.split(".")
    for index, part in enumerate(parts):
        if _is_private(part):
            return ".".join(parts[:index])
    return None


@dataclass(frozen=True, slots=True)
class ImportCycle:
    """Modules that import each other (a strongly connected component of the graph)."""

    modules: tuple[str, ...]
    path: tuple[ImportEdge, ...]
    """One cycle through them, from the first module back to it (the shortest)."""

    def __str__(self) -> str:
        steps = "".join(f"\n    {edge}" for edge in self.path)
        return f"  {len(self.modules)} modules: {', '.join(self.modules)}; one cycle:{steps}"


def import_cycles(edges: list[ImportEdge]) -> list[ImportCycle]:
    """Each set of more than one module that import each other, largest first."""
    graph: dict[str, dict[str, ImportEdge]] = {}
    for edge in edges:
        graph.setdefault(edge.importer, {}).setdefault(edge.target, edge)
        graph.setdefault(edge.target, {})
    cycles = [
        ImportCycle(tuple(sorted(c)), tuple(_cycle_through(sorted(c), graph)))
        for c in _components(graph)
        if len(c) > 1
    ]
    return sorted(cycles, key=lambda c: (-len(c.modules), c.modules))


def _components(graph: dict[str, dict[str, ImportEdge]]) -> Iterator[set[str]]:
    """Tarjan's strongly connected components, without recursion."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                yield component


def _cycle_through(members: list[str], graph: dict[str, dict[str, ImportEdge]]) -> list[ImportEdge]:
    """The shortest cycle from the first of ``members`` back to it (breadth first)."""
    start, inside = members[0], set(members)
    came: dict[str, ImportEdge] = {}
    frontier = [start]
    while frontier:
        after = []
        for node in frontier:
            for target, edge in sorted(graph[node].items()):
                if target not in inside or target in came:
                    continue
                came[target] = edge
                if target == start:
                    path = [edge]
                    while path[0].importer != start:
                        path.insert(0, came[path[0].importer])
                    return path
                after.append(target)
        frontier = after
    raise AssertionError(f"no cycle through {members}")  # a component always has one


SRC_ROOT: Final = SRC.parent
"""The directory holding the package (``src``)."""


def test_no_import_cycle_in_the_package() -> None:
    edges, _ = package_imports(SRC_ROOT)
    cycles = import_cycles(edges)
    assert not cycles, (
        f"{len(cycles)} import cycle(s), counting imports in functions and under "
        "TYPE_CHECKING; break each (move the shared part into a module both import, or "
        "let the caller pass it in):\n" + "\n".join(str(c) for c in cycles)
    )


def test_no_private_name_is_imported_from_another_module() -> None:
    _, private = package_imports(SRC_ROOT)
    assert not private, (
        f"{len(private)} private name(s) imported across modules; make each public in "
        "a module that owns it (a name without the underscore), or keep its users in "
        "its module:\n" + "\n".join(f"  {p}" for p in private)
    )


# ------------------------------------------------------------------ the graph checker


def _tree(tmp_path: Path, files: dict[str, str]) -> Path:
    """A package ``pymotoros`` under ``tmp_path`` with ``files`` (path -> source)."""
    for name, source in {"__init__.py": "", **files}.items():
        path = tmp_path / PACKAGE / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(source, encoding="utf-8")
    return tmp_path


@pytest.mark.parametrize(
    "b_imports_a",
    [
        "from pymotoros.a import f\n",
        "def g():\n    from pymotoros import a\n",
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import f\n",
        "import pymotoros.a\n",
    ],
    ids=["top", "in a function", "TYPE_CHECKING", "import statement"],
)
def test_a_cycle_is_found_however_it_is_imported(tmp_path: Path, b_imports_a: str) -> None:
    src = _tree(
        tmp_path,
        {"a.py": "from pymotoros.c import h\ndef f(): ...\n", "c.py": "import pymotoros.b\n"},
    )
    (src / PACKAGE / "b.py").write_text(b_imports_a, encoding="utf-8")
    cycles = import_cycles(package_imports(src)[0])
    assert [c.modules for c in cycles] == [("pymotoros.a", "pymotoros.b", "pymotoros.c")]
    assert [e.importer for e in cycles[0].path] == ["pymotoros.a", "pymotoros.c", "pymotoros.b"]
    assert "3 modules: pymotoros.a, pymotoros.b, pymotoros.c; one cycle:" in str(cycles[0])
    assert "pymotoros.b -> pymotoros.a (line " in str(cycles[0])


def test_the_parent_package_and_a_one_way_chain_are_no_cycle(tmp_path: Path) -> None:
    src = _tree(
        tmp_path,
        {
            "pkg/__init__.py": "from pymotoros.pkg.one import f\n",
            "pkg/one.py": "from pymotoros.pkg.two import g\ndef f(): ...\n",
            "pkg/two.py": "from . import three\ndef g(): ...\n",  # the module, not pkg
            "pkg/three.py": "import os\n",
        },
    )
    edges, _ = package_imports(src)
    assert import_cycles(edges) == []
    assert {(e.importer, e.target) for e in edges} == {
        ("pymotoros.pkg", "pymotoros.pkg.one"),
        ("pymotoros.pkg.one", "pymotoros.pkg.two"),
        ("pymotoros.pkg.two", "pymotoros.pkg.three"),
    }


def test_two_separate_cycles_are_both_named(tmp_path: Path) -> None:
    src = _tree(
        tmp_path,
        {
            "a.py": "from pymotoros import b\n",
            "b.py": "from pymotoros import a\n",
            "x/__init__.py": "from pymotoros.x.y import z\n",
            "x/y.py": "def f():\n    from pymotoros.x import w\n",
        },
    )
    cycles = import_cycles(package_imports(src)[0])
    assert [c.modules for c in cycles] == [
        ("pymotoros.a", "pymotoros.b"),
        ("pymotoros.x", "pymotoros.x.y"),
    ]


def test_private_names_and_modules_across_modules_are_found(tmp_path: Path) -> None:
    src = _tree(
        tmp_path,
        {
            "p/__init__.py": "",
            "p/_base.py": "_HIDDEN = 1\nSHOWN = 2\n",
            "p/ok.py": "from ._base import SHOWN\nfrom pymotoros.p import _base\n",
            "p/leaky.py": "from ._base import _HIDDEN\n",
            "q.py": "def f():\n    from pymotoros.p._base import SHOWN\n",
            "r.py": "from pymotoros import __version__\nfrom pymotoros.p.ok import _x as x\n",
        },
    )
    _, private = package_imports(src)
    assert sorted(str(p) for p in private) == [
        "pymotoros.p.leaky imports _HIDDEN from pymotoros.p._base (line 1)",
        "pymotoros.q imports _base from pymotoros.p (line 2)",
        "pymotoros.r imports _x from pymotoros.p.ok (line 2)",
    ]
