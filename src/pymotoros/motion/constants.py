"""Fixed numbers of MotoROS 1.9.12's motion code, each with the section that names it.

Section numbers refer to ``shared/reference/motoros-1.9.12.md``. The rules the client
shares (the slot count, the start tolerance, the 4-hour limit) live in
:mod:`pymotoros.models.rules`.
"""

from __future__ import annotations

from typing import Final

from pymotoros.models.rules import SLOTS as SLOTS
from pymotoros.protocol.constants import INT32_MAX as _INT32_MAX
from pymotoros.protocol.constants import INT32_MIN as _INT32_MIN

QUEUE_SIZE: Final = 200
"""Increments one group's queue holds (Q_SIZE, §5.1): 0.8 s at 4 ms."""

INT32_MIN: Final = _INT32_MIN
INT32_MAX: Final = _INT32_MAX
"""C's int range, as on the wire (``protocol.constants``)."""
