"""Helpers shared by the motion tests."""

from __future__ import annotations

import numpy as np

from pymotoros.models import controller_model, robot_model
from pymotoros.motion import GroupAxes, TrajPoint, numerics
from pymotoros.motion.numerics import LD


def axes_for(robot: str = "hc10", controller: str = "yrc1000", **kw: object) -> GroupAxes:
    return GroupAxes.from_model(
        robot_model(robot).groups[0],
        controller_model(controller),
        **kw,  # type: ignore[arg-type]
    )


def still(time: float, pos: tuple[float, ...], n: int = 6) -> TrajPoint:
    """A point with zero velocity."""
    return TrajPoint(time, pos, (0.0,) * n)


def x87_positions(
    x0: list[float], v0: list[float], x1: list[float], v1: list[float], t: float, taus: list[float]
) -> list[tuple[float, ...]]:
    """The x87's float32 positions: coefficients and positions in longdouble."""
    coef = numerics.coefficients_x87_exact(x0, v0, x1, v1, t)
    n = len(x0)
    lt = np.array(taus, dtype=np.float64).reshape(-1, 1).astype(LD)
    pos = numerics.positions_x87(
        np.array(x0, dtype=LD),
        np.array(v0, dtype=LD),
        np.array([c / 2 for c in coef[:n]], dtype=LD),
        np.array(coef[n:], dtype=LD),
        lt,
        lt * lt,
    )
    return [tuple(row) for row in pos.tolist()]
