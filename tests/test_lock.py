"""requirements/test.lock holds every test dependency that pyproject.toml names, at a
version pyproject.toml allows, and says how it was made.

.ci/run installs the lock into a fresh virtual environment before the README's
``pip install -e ".[test]"``: a dependency added to pyproject.toml but missing from the
lock would be resolved afresh there (to whatever is newest that day), which is what the
lock is for preventing. This fails first, naming the package and the command that
regenerates the lock (docs/testing.md).
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "requirements" / "test.lock"
PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==([^\s\\;]+)", re.MULTILINE)


def regenerate_command() -> str:
    """The command in the lock's header (the line after "via the following command")."""
    lines = LOCK.read_text().splitlines()
    for number, line in enumerate(lines[:5]):
        if "following command" in line:
            return lines[number + 1].lstrip("# ").strip()
    raise AssertionError(f"{LOCK.name} names no command in its header: {lines[:3]}")


def pinned() -> dict[str, Version]:
    return {canonicalize_name(name): Version(version) for name, version in PIN.findall(
        LOCK.read_text())}  # fmt: skip


def declared() -> list[Requirement]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    return [Requirement(r) for r in [*project["dependencies"],
                                     *project["optional-dependencies"]["test"]]]  # fmt: skip


def test_every_declared_dependency_is_pinned_at_an_allowed_version() -> None:
    pins = pinned()
    command = regenerate_command()
    missing = [str(r) for r in declared() if canonicalize_name(r.name) not in pins]
    assert not missing, (
        f"{LOCK.relative_to(ROOT)} lacks {missing}: regenerate it from the repository "
        f"root with `{command}`"
    )
    outside = [
        f"{r.name}=={pins[canonicalize_name(r.name)]} (pyproject.toml: {r})"
        for r in declared()
        if not r.specifier.contains(pins[canonicalize_name(r.name)], prereleases=True)
    ]
    assert not outside, f"pinned outside pyproject.toml's range: {outside}; run `{command}`"


def test_everything_in_it_is_pinned_and_hashed() -> None:
    """An indirect dependency is locked too (pip's hash-checking mode needs all of
    them), and the package itself is not in it (CI installs the checkout)."""
    text = LOCK.read_text()
    requirements = [
        line for line in text.splitlines() if line and not line.startswith((" ", "#"))
    ]
    assert requirements, "the lock is empty"
    assert all("==" in line for line in requirements), requirements
    assert text.count("--hash=sha256:") >= len(requirements)
    assert "pymotoros" not in pinned()
    assert len(pinned()) > len(declared())  # the indirect ones are there


def test_the_regenerate_command_is_documented() -> None:
    command = regenerate_command()
    assert command.startswith("uv pip compile pyproject.toml"), command
    assert "--output-file requirements/test.lock" in command
    assert command in (ROOT / "docs" / "testing.md").read_text()
