"""Joint values in words, with their units (rad or m per axis): what every message
of the client that quotes positions, distances or a refusal's numbers says.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from pymotoros.client.errors import (
    AxisDeviation,
)
from pymotoros.models import GroupModel
from pymotoros.models.rules import START_TOLERANCE_PULSES


def deviation_text(
    devs: Sequence[AxisDeviation], kind: str, models: Sequence[GroupModel] = ()
) -> str:
    """The numbers of a refusal with their units (rad, rad/s; m, m/s for a linear axis
    of ``models``, the refused groups' models in order)."""
    linear = {i for i, a in enumerate(a for m in models for a in m.axes) if a.linear}
    if kind == "start":
        return "; ".join(
            f"{d.name} {d.pulses} pulses ({d.difference:+.5f} "
            f"{'m' if d.axis in linear else 'rad'}) from the robot, "
            f"tolerance {START_TOLERANCE_PULSES} pulses"
            for d in devs
        )
    return "; ".join(
        f"{d.name} {d.value:+.4f} {unit} > limit {d.reference:.4f} {unit}"
        for d in devs
        for unit in ("m/s" if d.axis in linear else "rad/s",)
    )


def joint_values_text(
    positions: Sequence[float], models: Sequence[GroupModel], *, deg: bool = False
) -> str:
    """``[0.5724, 0.0000, …] rad`` (``rad``/``m`` after each value when a linear axis is
    among them; ``deg`` for the rotary axes with ``deg``): joint values with their
    units, as every message of the client gives them."""
    axes = [a for m in models for a in m.axes]
    rotary = "deg" if deg else "rad"

    def value(v: float, linear: bool) -> str:
        return f"{v if linear or not deg else math.degrees(v):.4f}"

    if len(axes) != len(positions):
        return "[" + ", ".join(f"{v:.4f}" for v in positions) + "] (rad/m)"
    if not any(a.linear for a in axes):
        return "[" + ", ".join(value(v, False) for v in positions) + f"] {rotary}"
    return (
        "["
        + ", ".join(
            f"{value(v, a.linear)} {'m' if a.linear else rotary}"
            for v, a in zip(positions, axes, strict=True)
        )
        + "]"
    )


def farthest_text(
    positions: Sequence[float], goal: Sequence[float], models: Sequence[GroupModel]
) -> str:
    """The largest joint distance to ``goal`` with its unit and joint: ``0.1056 rad
    (joint_1_s)``, as every message that says how far the robot is from a goal gives it."""
    axes = [a for m in models for a in m.axes]
    gaps = [abs(p - g) for p, g in zip(positions, goal, strict=True)]
    if not gaps:
        return "0 rad"
    i = max(range(len(gaps)), key=gaps.__getitem__)
    if len(axes) != len(gaps):
        return f"{gaps[i]:.4f} rad/m (axis {i + 1})"
    return f"{gaps[i]:.4f} {'m' if axes[i].linear else 'rad'} ({axes[i].name})"
