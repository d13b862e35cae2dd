"""Helpers shared by the motion tests."""

from __future__ import annotations

from pymotoros.models import controller_model, robot_model
from pymotoros.motion import GroupAxes, TrajPoint


def axes_for(robot: str = "hc10", controller: str = "yrc1000", **kw: object) -> GroupAxes:
    return GroupAxes.from_model(
        robot_model(robot).groups[0],
        controller_model(controller),
        **kw,  # type: ignore[arg-type]
    )


def still(time: float, pos: tuple[float, ...], n: int = 6) -> TrajPoint:
    """A point with zero velocity."""
    return TrajPoint(time, pos, (0.0,) * n)
