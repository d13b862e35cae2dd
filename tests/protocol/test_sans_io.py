"""The codec is sans-I/O: importing it must not pull in asyncio or socket (STYLE B2.1)."""

from __future__ import annotations

import subprocess
import sys

import pymotoros.protocol

FORBIDDEN = ("asyncio", "socket", "selectors", "ssl")


def _loaded_after(prelude: str) -> list[str]:
    """Forbidden modules that importing the protocol package adds after ``prelude``."""
    code = (
        "import sys\n"
        f"{prelude}\n"
        "before = set(sys.modules)\n"
        "import pymotoros.protocol, pymotoros.protocol.sizes\n"
        f"print(','.join(m for m in {FORBIDDEN!r} if m in sys.modules and m not in before))\n"
    )
    result = subprocess.run(  # noqa: S603 - fixed interpreter and code
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=60
    )
    return [m for m in result.stdout.strip().split(",") if m]


def test_protocol_modules_load_neither_asyncio_nor_socket() -> None:
    """The protocol layer itself (after the root package) adds no I/O module."""
    assert _loaded_after("import pymotoros") == []


def test_fresh_import_loads_neither_asyncio_nor_socket() -> None:
    assert _loaded_after("") == []


def test_public_names_exist() -> None:
    for name in pymotoros.protocol.__all__:
        assert hasattr(pymotoros.protocol, name), name
