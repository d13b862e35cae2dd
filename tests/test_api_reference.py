"""The API reference: every public name has a docstring, and the site builds without a
warning (``mkdocs build --strict``), naming every public name.

"Public" is the package's own curated surface, read from the package itself, never a
copy of it: the front door's ``pymotoros.__all__``, ``pymotoros.client.__all__``,
``pymotoros.protocol.__all__`` (with the messages it re-exports), ``pymotoros.testing``'s
and the pytest plugin's ``__all__``, and every exception class of ``pymotoros.errors``;
for each public class, its public methods and properties, inherited ones included.

The docstrings are read with griffe, the same static reader mkdocstrings renders the
reference with, so "has a docstring" here means "shows a docstring on the page" (a
dataclass's generated ``__doc__`` or an ``Enum``'s default one would fool a run-time
check). Attribute docstrings (the string under a constant) count, as on the page.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

griffe = pytest.importorskip("griffe")  # the `test` extra installs it (with mkdocstrings)

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ROOT / "src"

CURATED_MODULES = (
    "pymotoros",
    "pymotoros.client",
    "pymotoros.protocol",
    "pymotoros.testing",
    "pymotoros.pytest_plugin",
)
"""Modules whose ``__all__`` is public API (``docs/architecture.md``: the front door, the
in-memory twin and the pytest plugin; the client and the codec are the two sub-packages a
user imports from directly, as ``docs/client.md`` and ``docs/protocol.md`` do)."""

NOT_IN_SOURCE = frozenset({"pymotoros.__version__"})
"""Public names a static reader cannot see: ``__version__`` is computed on first use (PEP
562, from the installed distribution); docs/api/index.md says what it holds."""

BUILD_BUDGET_S = 120.0
"""Longest the reference's build may take (measured: about 4 s of CPU, 4 to 15 s of wall
time on the shared 2-core development machine)."""


EXTENSION = ROOT / "docs" / "griffe_reference.py"
"""The griffe extension mkdocs.yml loads: the check reads the API as the pages show it
(``SyncRobotClient.move_joints`` a documented blocking method)."""


@functools.cache
def _load() -> object:
    extensions = griffe.load_extensions(str(EXTENSION))
    loader = griffe.GriffeLoader(search_paths=[str(SOURCES)], extensions=extensions)
    package = loader.load("pymotoros")
    loader.resolve_aliases(implicit=False, external=False)
    return package


def public_names() -> list[str]:
    """Every public name, as the path a user imports it by (``pymotoros.client.Ports``)."""
    names: set[str] = set()
    for module_name in CURATED_MODULES:
        module = importlib.import_module(module_name)
        names.update(f"{module_name}.{name}" for name in module.__all__)
    errors = importlib.import_module("pymotoros.errors")
    names.update(
        f"pymotoros.errors.{name}"
        for name, value in vars(errors).items()
        if isinstance(value, type)
        and issubclass(value, BaseException)
        and value.__module__ == errors.__name__
        and not name.startswith("_")
    )
    return sorted(names - NOT_IN_SOURCE)


def _lookup(package: object, path: str) -> object:
    """The griffe object of a public path, followed through re-exports to its definition.
    The front door re-exports lazily (a table griffe cannot run), so its names are looked
    up where ``pymotoros._EXPORTS`` says they are defined."""
    module, _, name = path.rpartition(".")
    if module == "pymotoros":
        front_door = importlib.import_module("pymotoros")
        module = front_door._WHERE[name]
    obj = package[module.removeprefix("pymotoros.") + "." + name]  # type: ignore[index]
    return obj.final_target if obj.is_alias else obj  # type: ignore[attr-defined]


def _is_documented(obj: object) -> bool:
    docstring = obj.docstring  # type: ignore[attr-defined]
    return docstring is not None and bool(docstring.value.strip())


def _public_members(cls: object) -> list[tuple[str, object]]:
    """A class's public methods and properties, its own and those it inherits from other
    pymotoros classes (the page shows both)."""
    members = []
    for name, member in cls.all_members.items():  # type: ignore[attr-defined]
        if name.startswith("_"):
            continue
        target = member.final_target if member.is_alias else member
        if target.is_function or (target.is_attribute and "property" in target.labels):
            members.append((name, target))
    return members


def undocumented() -> list[str]:
    """Each undocumented definition once, with the first public path that shows it."""
    package = _load()
    missing: dict[str, str] = {}
    for path in public_names():
        obj = _lookup(package, path)
        if not _is_documented(obj):
            missing.setdefault(obj.path, path)  # type: ignore[attr-defined]
        if obj.is_class:  # type: ignore[attr-defined]
            for name, member in _public_members(obj):
                if not _is_documented(member):
                    missing.setdefault(member.path, f"{path}.{name}")  # type: ignore[attr-defined]
    return [f"{shown} (defined at {where})" for where, shown in sorted(missing.items())]


def test_the_public_surface_is_found() -> None:
    """The walk sees the names users know, so an empty 'undocumented' list means something."""
    names = set(public_names())
    for known in (
        "pymotoros.RobotClient",
        "pymotoros.client.StreamStats",
        "pymotoros.protocol.FrameDecoder",
        "pymotoros.protocol.MotoMotionCtrl",
        "pymotoros.testing.twin",
        "pymotoros.pytest_plugin.pymotoros_twin",
        "pymotoros.errors.PymotorosError",
    ):
        assert known in names, known
    package = _load()
    members = dict(_public_members(_lookup(package, "pymotoros.SyncRobotClient")))
    assert {"move_joints", "enable", "close"} <= set(members)


def test_every_public_name_has_a_docstring() -> None:
    missing = undocumented()
    assert not missing, (
        f"{len(missing)} public names have no docstring (say what it is or does, and why,"
        " with units):\n  " + "\n  ".join(missing)
    )


# --- the build ----------------------------------------------------------------------------


def _mkdocs() -> list[str]:
    pytest.importorskip("mkdocs")
    pytest.importorskip("mkdocstrings_handlers.python")
    return [sys.executable, "-m", "mkdocs"]


@pytest.mark.timeout(BUILD_BUDGET_S + 60)
def test_the_reference_builds_without_a_warning_and_names_every_public_name(
    tmp_path: Path,
) -> None:
    """``mkdocs build --strict``: any warning (a broken cross-reference, a docstring
    mkdocstrings cannot parse, a page outside the navigation) fails the build. The site
    goes to tmp_path, so the checkout is left as it was."""
    site = tmp_path / "site"
    start = time.monotonic()
    done = subprocess.run(  # noqa: S603 - our own build
        [
            *_mkdocs(),
            "build",
            "--strict",
            "--config-file",
            str(ROOT / "mkdocs.yml"),
            "--site-dir",
            str(site),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=BUILD_BUDGET_S,
        check=False,
    )
    seconds = time.monotonic() - start
    print(f"mkdocs build --strict: {seconds:.1f} s")
    assert done.returncode == 0, done.stderr[-5000:]
    assert "WARNING" not in done.stderr, done.stderr[-5000:]
    html = "\n".join(page.read_text() for page in site.rglob("*.html"))
    anchors = set(re.findall(r'id="(pymotoros\.[\w.]+)"', html))
    absent = [name for name in public_names() if not _shown(name, anchors)]
    assert not absent, (
        "public names no page of docs/api/ shows (add a `::: path` line for each):\n  "
        + "\n  ".join(absent)
    )
    testing = (site / "testing.html").read_text()
    for name in _plugin_names():
        assert name in testing, f"the testing page does not document the plugin's {name!r}"
    remote = sorted(
        set(re.findall(r'<(?:script|link|img)[^>]+(?:src|href)="(https?://[^"]+)"', html))
    )
    assert not remote, f"the pages load files from the network: {remote}"


def _plugin_names() -> list[str]:
    """The pytest plugin's marker and ini options, as the plugin registers them."""
    plugin = importlib.import_module("pymotoros.pytest_plugin")
    names = [f"@pytest.mark.{plugin.MARKER}("]

    class Parser:
        def addini(self, name: str, *args: object, **kwargs: object) -> None:
            names.append(name)

        def addoption(self, *names_: str, **kwargs: object) -> None:
            names.extend(names_)

    plugin.pytest_addoption(Parser())
    return names


def _shown(path: str, anchors: set[str]) -> bool:
    """A name is shown under the path users import it by, or under another path to the
    same definition (each object is on one page only, or cross-references to it would be
    ambiguous): the front door's names under their sub-package's (``pymotoros.client.Ports``,
    ``pymotoros.models.RobotModel``), ``pymotoros.DhLink`` as ``pymotoros.protocol.DhLink``."""
    if path in anchors:
        return True
    target = _definition(path)
    return any(_definition(anchor) == target for anchor in anchors if _is_object(anchor))


def _is_object(anchor: str) -> bool:
    try:
        _definition(anchor)
    except (KeyError, ValueError, AttributeError, griffe.AliasResolutionError):
        return False
    return True


@functools.cache
def _definition(path: str) -> str:
    """Where a public path's object is defined (``pymotoros.client.robot.RobotClient``); the
    front door's names through the table of ``pymotoros._EXPORTS``."""
    module, _, name = path.rpartition(".")
    if module == "pymotoros":
        module = importlib.import_module("pymotoros")._WHERE[name]
    obj = _load()[module.removeprefix("pymotoros.") + "." + name]  # type: ignore[index]
    return str((obj.final_target if obj.is_alias else obj).path)


def test_the_build_is_offline() -> None:
    """No theme, inventory or plugin fetched at build time: the configuration names no
    remote address (the build in CI and on a laptop without network is the same)."""
    config = (ROOT / "mkdocs.yml").read_text()
    assert not re.search(r"https?://", config.split("site_url", 1)[0]), config
    assert "import:" not in config, "external inventories are fetched over the network"


def test_the_reference_pages_hold_no_block_the_docs_runner_would_miss() -> None:
    """tests/test_docs_run.py runs the code of README.md and docs/*.md, not docs/api/: a
    runnable block there would never run. The only one allowed is the build commands,
    which the build test above runs (``mkdocs serve`` is the same build, served)."""
    pages = sorted((ROOT / "docs" / "api").glob("*.md"))
    assert pages, "docs/api/ has no pages"
    fence = re.compile(r"^```(\w*)\n(.*?)^```", re.MULTILINE | re.DOTALL)
    commands = []
    for page in pages:
        for language, body in fence.findall(page.read_text()):
            assert language in ("sh", "text", ""), f"{page.name}: a {language!r} block"
            if language == "sh":
                commands += [line.split("#")[0].strip() for line in body.splitlines()]
    assert {c for c in commands if c} == {"mkdocs serve", "mkdocs build --strict"}, commands


def test_sphinx_roles_are_written_as_markdown() -> None:
    """The docstrings' reST markup would show raw on a Markdown page: a role becomes the
    name in code, an optional link where the target resolves; ``::`` a colon."""
    spec = importlib.util.spec_from_file_location("griffe_reference", EXTENSION)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    text = (
        "See :class:`~pymotoros.client.RobotClient` and :meth:`Motion.stop`. Front door::\n\n    x"
    )
    assert module.markdown(text) == (
        "See <code>RobotClient</code> and <code>Motion.stop</code>. Front door:\n\n    x"
    )
    linked = module.markdown(":class:`~pymotoros.client.RobotClient`", lambda target: target)
    assert linked == (
        '<autoref identifier="pymotoros.client.RobotClient" optional>'
        "<code>RobotClient</code></autoref>"
    )
    assert module.markdown("Tree:\n\n::\n\n    a") == "Tree:\n\n\n\n    a"
