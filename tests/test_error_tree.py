"""Every public exception class of the package is rooted in :class:`PymotorosError`.

``errors.py`` promises one exception tree: a caller that catches ``PymotorosError``
catches every error pymotoros raises on purpose. The front-door test checks only the
names exported by ``import pymotoros``; this one walks every module, so a public error
declared next to its code (``RecordingError``, ``PflRefusedError`` …) cannot escape.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import pymotoros
from pymotoros.errors import PymotorosError


def _public_exceptions() -> dict[str, type[BaseException]]:
    found: dict[str, type[BaseException]] = {}
    for info in pkgutil.walk_packages(pymotoros.__path__, "pymotoros."):
        if info.name.rsplit(".", 1)[-1] == "__main__":
            continue  # running it would start the CLI
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if (
                not name.startswith("_")
                and inspect.isclass(value)
                and issubclass(value, BaseException)
                and value.__module__ == module.__name__
            ):
                found[f"{module.__name__}.{name}"] = value
    return found


def test_every_public_exception_is_a_pymotoros_error() -> None:
    exceptions = _public_exceptions()
    assert "pymotoros.client.recording.RecordingError" in exceptions
    assert "pymotoros.controller.safety.pfl.PflRefusedError" in exceptions
    outside = sorted(n for n, cls in exceptions.items() if not issubclass(cls, PymotorosError))
    assert not outside, f"public exceptions outside the PymotorosError tree: {outside}"


@pytest.mark.parametrize(
    "where",
    [
        "pymotoros.client.recording.RecordingError",
        "pymotoros.controller.safety.pfl.PflRefusedError",
        "pymotoros.runtime.strict_json.DuplicateKeyError",
    ],
)
def test_refusals_are_still_value_errors(where: str) -> None:
    """The HTTP API and scenarios refuse a ``ValueError`` as a bad value; keep that working."""
    module, name = where.rsplit(".", 1)
    cls = getattr(importlib.import_module(module), name)
    assert issubclass(cls, ValueError)
    assert issubclass(cls, PymotorosError)
