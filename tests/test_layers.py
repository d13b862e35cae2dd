"""The import rules of docs/architecture.md, checked on the source tree."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "pymotoros"

# layer -> layers it must never import. ``pymotoros.testing`` (the in-memory twin) is a
# top layer like the CLI: it may import anything, and nothing imports it.
FORBIDDEN: dict[str, tuple[str, ...]] = {
    "protocol": ("models", "motion", "controller", "runtime", "client", "cli", "web", "testing"),
    "models": ("motion", "controller", "runtime", "client", "cli", "web", "testing"),
    "motion": (
        "controller",
        "runtime",
        "client",
        "cli",
        "web",
        "protocol.messages",
        "protocol.framing",
        "testing",
    ),
    "controller": (
        "runtime",
        "client",
        "cli",
        "web",
        "protocol.messages",
        "protocol.framing",
        "testing",
    ),
    "kinematics": (
        "motion",
        "controller",
        "runtime",
        "client",
        "cli",
        "web",
        "protocol.messages",
        "protocol.framing",
        "testing",
    ),
    "runtime": ("client", "cli", "web", "testing"),
    "client": ("controller", "runtime", "motion", "cli", "web", "testing", "trajectory"),
    # trajectory files, planning and the offline check: on top of models and motion
    "trajectory": ("controller", "runtime", "client", "cli", "web", "testing"),
    "cli": ("testing",),
    # the pcapng writer of the session recorder: bytes and ports only, so that both the
    # client and the runtime (``sim --record``) can import it
    "capture": (
        "protocol",
        "models",
        "motion",
        "kinematics",
        "controller",
        "runtime",
        "client",
        "trajectory",
        "cli",
        "web",
        "testing",
    ),
}


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
    return found


def _modules(layer: str) -> list[Path]:
    if (SRC / f"{layer}.py").is_file():  # a one-module layer (capture)
        return [SRC / f"{layer}.py"]
    return sorted((SRC / layer).rglob("*.py"))


def test_nothing_in_the_package_imports_the_testing_module() -> None:
    importers = [
        str(path.relative_to(SRC))
        for path in SRC.rglob("*.py")
        if path.name != "testing.py"
        and any(
            n == "pymotoros.testing" or n.startswith("pymotoros.testing.") for n in _imports(path)
        )
    ]
    assert not importers


@pytest.mark.parametrize("layer", sorted(FORBIDDEN))
def test_layer_imports_only_what_it_may(layer: str) -> None:
    violations = []
    for path in _modules(layer):
        for name in _imports(path):
            for banned in FORBIDDEN[layer]:
                if name == f"pymotoros.{banned}" or name.startswith(f"pymotoros.{banned}."):
                    violations.append(f"{path.relative_to(SRC)} imports {name}")
    assert not violations, "\n".join(violations)


def test_every_layer_has_modules() -> None:
    for layer in FORBIDDEN:
        assert _modules(layer), f"no modules in {layer}"
