"""The FSU joint-speed clip, written once for the twin and the offline check.

The Functional Safety Unit belongs to the controller, not to MotoROS: with a joint-speed
limit of ``pct`` % it lets each axis move at most that share of the axis's maximum
increment per tick (maxInc, reference §5.5), and at least one pulse, so a limit never
stops an axis outright; MotoROS 1.9.12 resends what was dropped (reference §5.6 step 3).
``controller/safety/fsu.py`` (the twin) and ``trajectory/check.py`` (``pymotoros check
--fsu``) both call :func:`fsu_joint_clip`, so the two cannot drift apart; the tests pin
its numbers by hand (tests/models/test_fsu_formula.py).
"""

from __future__ import annotations

from collections.abc import Sequence


def fsu_joint_clip(max_increment: Sequence[int], pct: int) -> tuple[int, ...]:
    """Per slot, the most pulses a joint-speed limit of ``pct`` % lets an axis execute in
    one tick: ``max(1, maxInc × pct // 100)``, and 0 for a slot without an axis (maxInc 0)."""
    return tuple(max(1, m * pct // 100) if m else 0 for m in max_increment)
