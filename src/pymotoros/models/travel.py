"""How often a moving robot's workspace must be checked: the first tick by which it can
have closed the clearance the last check found.

Its own module (numpy) so that ``models.workspace``, which light modules import, stays
free of numpy (``tests/test_shared_rules.py::test_shared_homes_stay_numpy_free``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

import numpy as np
import numpy.typing as npt

TRAVEL_WINDOW_TICKS: Final = 64
"""Ticks of travel summed first when looking for the next contact check (doubled each
round): near an obstacle the next check is a few ticks away, far from all of them
hundreds or thousands."""


def tick_travel_reaches(
    travel: Callable[[int, int], npt.NDArray[np.float64]], start: int, ticks: int, distance: float
) -> int:
    """The first tick after ``start`` by which the robot may have moved ``distance`` (m):
    ``travel(a, b)`` gives how far any point of it can move in each tick from ``a`` to
    ``b`` (a bound from |Δq| and the lever arms). ``ticks`` when it never does.

    Shared by the client's guard (``kinematics.sweep``) and the offline check
    (``trajectory.collisions``), which check the workspace only as often as the robot
    can have closed the clearance the last check found."""
    done = 0.0
    window = TRAVEL_WINDOW_TICKS
    while start < ticks - 1:
        end = min(ticks - 1, start + window)
        window *= 2
        total = done + np.cumsum(travel(start, end))
        j = int(np.searchsorted(total, distance, side="left"))
        if j < len(total):
            return start + j + 1
        done = float(total[-1])
        start = end
    return ticks
