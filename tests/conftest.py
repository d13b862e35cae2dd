"""The project's own tests use the ``pymotoros_twin`` fixture like any user does.

Installing pymotoros registers its pytest plugin (the ``pytest11`` entry point in
pyproject.toml), and registering it twice is an error. Only where the entry point is
absent (a source tree run with ``PYTHONPATH=src`` against an install made before the
entry point existed) or entry points are not loaded at all
(``PYTEST_DISABLE_PLUGIN_AUTOLOAD``) is it named here; ``pytest --trace-config`` shows
which of the two loaded it.
"""

from __future__ import annotations

import os
from importlib.metadata import entry_points


def _registered_by_installation() -> bool:
    if os.environ.get("PYTEST_DISABLE_PLUGIN_AUTOLOAD"):
        return False
    return any(ep.value == "pymotoros.pytest_plugin" for ep in entry_points(group="pytest11"))


if not _registered_by_installation():
    pytest_plugins = ["pymotoros.pytest_plugin"]

# In CI a skip is a failure; a run that changes the source tree is reported (tests/ci_guard.py).
from ci_guard import (  # noqa: E402
    pytest_make_collect_report,
    pytest_runtest_makereport,
    pytest_sessionfinish,
    pytest_sessionstart,
)

__all__ = [
    "pytest_make_collect_report",
    "pytest_runtest_makereport",
    "pytest_sessionfinish",
    "pytest_sessionstart",
]
