"""Reading the project's TOML files (cell, settings, scenario) one way, with one error shape.

Every file a user writes by hand fails the same way: a :class:`~pymotoros.errors.ConfigError`
that starts with the file's path and says what is wrong (``cell.toml: cannot read the cell
file (No such file or directory)``, ``cell.toml: not valid TOML: ...``,
``cell.toml: groups[1].robot: must be a string, not 5``). It sits in the models layer,
which every layer that reads such a file may import (the cell file is read by the models
themselves, the settings by the CLI, a scenario by the controller).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TypeVar

from pymotoros.errors import ConfigError, PymotorosError

__all__ = ["TomlTable", "read_text_file", "read_toml"]

_T = TypeVar("_T")


def read_text_file(
    p: Path,
    what: str,
    *,
    encoding: str = "utf-8",
    not_text: str = "",
    error: Callable[[str], PymotorosError] = ConfigError,
) -> str:
    """The text of a file a user wrote by hand (a TOML file, a JBI job), or ``error``
    with the path and what went wrong; ``what`` names it (``"cell file"``), ``not_text``
    replaces "the WHAT is not UTF-8 text" when the bytes do not decode."""
    try:
        return p.read_text(encoding=encoding)
    except OSError as exc:
        raise error(f"{p}: cannot read the {what} ({exc.strerror or exc})") from exc
    except UnicodeDecodeError as exc:
        problem = not_text or f"the {what} is not UTF-8 text"
        raise error(f"{p}: {problem} ({exc.reason})") from exc


def read_toml(path: str | Path, what: str) -> dict[str, object]:
    """The parsed TOML file ``path``; ``what`` names it in errors (``"cell file"``)."""
    p = Path(path)
    text = read_text_file(p, what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{p}: not valid TOML: {exc}") from exc


class TomlTable:
    """A parsed TOML table with its key path, so that every error names the key
    (``groups[1].tools[0].tcp_m``), and the keys read, so that :meth:`finish` refuses
    the ones nobody reads (a misspelt key is an error, never silently ignored)."""

    def __init__(self, data: object, path: str, source: str) -> None:
        if not isinstance(data, Mapping):
            raise ConfigError(f"{source}: {path or 'the file'} must be a table")
        self.data: Mapping[str, object] = data
        self.path = path
        self.source = source
        self.used: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def error(self, name: str, problem: str) -> ConfigError:
        return ConfigError(f"{self.source}: {self.key(name)}: {problem}")

    def get(self, name: str) -> object:
        self.used.add(name)
        return self.data.get(name)

    def _typed(self, name: str, default: _T, kind: type[_T], described: str) -> _T:
        """The value at ``name`` if it is a ``kind`` (``described`` in the error), or
        ``default`` when the key is absent."""
        v = self.get(name)
        if v is None:
            return default
        if not isinstance(v, kind):
            raise self.error(name, f"must be {described}, not {v!r}")
        return v

    def string(self, name: str, default: str) -> str:
        return self._typed(name, default, str, "a string")

    def boolean(self, name: str, default: bool) -> bool:
        return self._typed(name, default, bool, "true or false")

    def integer(self, name: str, default: int, lo: int, hi: int) -> int:
        v = self.optional_integer(name, lo, hi)
        return default if v is None else v

    def optional_integer(self, name: str, lo: int, hi: int) -> int | None:
        """The integer at ``name`` within ``lo..hi``, or None when the key is absent."""
        v = self.get(name)
        if v is None:
            return None
        if not isinstance(v, int) or isinstance(v, bool):
            raise self.error(name, f"must be an integer, not {v!r}")
        if not lo <= v <= hi:
            raise self.error(name, f"must lie in {lo}..{hi}, not {v}")
        return v

    def number(self, name: str, default: float) -> float:
        v = self.get(name)
        if v is None:
            return default
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise self.error(name, f"must be a finite number, not {v!r}")
        return float(v)

    def table(self, name: str) -> TomlTable:
        v = self.get(name)
        return TomlTable({} if v is None else v, self.key(name), self.source)

    def array(self, name: str) -> list[object]:
        return self._typed(name, [], list, "an array")

    def finish(self) -> None:
        """Refuse the first key (in sorted order) that nothing has read."""
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise self.error(unknown[0], "unknown key (misspelt?)")
