"""How faithfully the twin copies MotoROS 1.9.12 where the real controller is surprising.

``exact`` (the default) reproduces each deterministic deviation of ``docs/fidelity.md``
§1 as MotoROS 1.9.12 does it, so a client meets on the twin what it would meet on the
robot: a message split across two reads answered 3001, queues kept across a closed
motion connection and resumed by the next one, the previous reply sent again for an
unknown command, sizes taken from the message type. ``safe`` keeps the twin's kinder
behaviour (reassembly, queues cleared, INVALID answers). Undefined behaviour of the C
code (NaN velocities, writes out of bounds, races) is handled the safe way in both.

A value of the cell (``[motoros] fidelity``), of ``pymotoros sim --fidelity`` and of
``pymotoros.testing``'s twins, handed to whoever needs it: never a global.
"""

from __future__ import annotations

import enum
from typing import Final

__all__ = ["DEFAULT_FIDELITY", "Fidelity"]


class Fidelity(enum.StrEnum):
    """Where the twin differs from MotoROS 1.9.12: nowhere it can help (exact), or kindly (safe)."""

    EXACT = "exact"
    """As MotoROS 1.9.12 does it, wherever its behaviour is deterministic."""
    SAFE = "safe"
    """The twin's documented improvements (``docs/fidelity.md`` §1, column "safe")."""

    @classmethod
    def parse(cls, value: object, where: str = "fidelity") -> Fidelity:
        """``value`` as a setting, or a ValueError that names the choices."""
        if isinstance(value, cls):
            return value
        if isinstance(value, str):
            try:
                return cls(value.strip().lower())
            except ValueError:
                pass
        choices = " or ".join(repr(f.value) for f in cls)
        raise ValueError(f"{where} must be {choices}, not {value!r}")


DEFAULT_FIDELITY: Final = Fidelity.EXACT
"""Issue 31: the twin behaves like the robot unless asked to be kinder."""
