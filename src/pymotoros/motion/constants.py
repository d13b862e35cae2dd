"""Fixed numbers of MotoROS 1.9.12's motion code, each with the section that names it.

Section numbers refer to ``shared/reference/motoros-1.9.12.md``.
"""

from __future__ import annotations

from typing import Final

from pymotoros.protocol.constants import INT32_MAX as _INT32_MAX
from pymotoros.protocol.constants import INT32_MIN as _INT32_MIN
from pymotoros.protocol.constants import MAX_PULSE_AXES

SLOTS: Final = MAX_PULSE_AXES
"""Axis slots of a control group: every pulse array and point array has 8 (§1.4, §5.7)."""

QUEUE_SIZE: Final = 200
"""Increments one group's queue holds (Q_SIZE, §5.1): 0.8 s at 4 ms."""

START_TOLERANCE_PULSES: Final = 30
"""Largest |requested − commanded| pulse difference a trajectory start may have (§3.4, §5.1)."""

MAX_POINT_TIME_S: Final = 14400.0
"""JOINT_TRAJ_PT_FULL refuses a point time at or beyond 4 h with 3016 (§3.4)."""

INVALID_AXIS_FACTOR: Final = 1.0
"""Pulse ratio MotoROS uses for a slot with no axis (§5.7, the default branch)."""

INT32_MIN: Final = _INT32_MIN
INT32_MAX: Final = _INT32_MAX
"""C's int range, as on the wire (``protocol.constants``)."""
