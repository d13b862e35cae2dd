"""The Cartesian part of ``pymotoros move``: ``--pose`` and ``--relative`` targets."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Final, Literal

import click

from pymotoros.client import RobotClient
from pymotoros.client.streaming import FollowingSample, MoveResult

RELATIVE_KEYS: Final = ("dx", "dy", "dz", "drx", "dry", "drz")
"""Names accepted by ``--relative``: metres for dx, dy, dz; radians (degrees with --deg)
for drx, dry, drz."""


def parse_relative(items: Sequence[str], deg: bool) -> tuple[float, ...]:
    """``("dz=-0.05", "drx=10")`` → (dx, dy, dz, drx, dry, drz); a clear error otherwise."""
    values = dict.fromkeys(RELATIVE_KEYS, 0.0)
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip().lower()
        if not sep or key not in values:
            raise click.BadParameter(
                f"{item!r}: write KEY=VALUE with KEY one of {', '.join(RELATIVE_KEYS)}",
                param_hint="--relative",
            )
        try:
            value = float(text)
        except ValueError:
            raise click.BadParameter(
                f"{item!r}: {text!r} is not a number", param_hint="--relative"
            ) from None
        if not math.isfinite(value):
            raise click.BadParameter(f"{item!r}: must be finite", param_hint="--relative")
        values[key] = math.radians(value) if deg and key.startswith("dr") else value
    return tuple(values[k] for k in RELATIVE_KEYS)


def pose_from_args(values: Sequence[float], deg: bool) -> tuple[float, ...]:
    """X Y Z (m) RX RY RZ (rad, or deg with --deg) from the command line."""
    if len(values) != 6:
        raise click.UsageError(f"--pose needs X Y Z RX RY RZ (6 values), got {len(values)}")
    x, y, z, rx, ry, rz = values
    if deg:
        rx, ry, rz = (math.radians(a) for a in (rx, ry, rz))
    return (x, y, z, rx, ry, rz)


async def cartesian_move(
    client: RobotClient,
    *,
    pose: Sequence[float] | None,
    relative: Sequence[float] | None,
    linear: bool,
    frame: Literal["base", "tool"],
    tcp_speed_mm_s: float,
    group: int,
    speed_scale: float,
    accel_scale: float,
    on_progress: Callable[[FollowingSample], None],
) -> MoveResult:
    """A move to ``pose`` (base coordinates) or by ``relative``; straight with ``linear``
    (always for --relative unless the caller says otherwise)."""
    if relative is not None:
        return await client.move_relative(
            *relative,
            frame=frame,
            group=group,
            linear=linear,
            tcp_speed_mm_s=tcp_speed_mm_s,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
        )
    assert pose is not None  # noqa: S101 - the caller gives one of the two
    if linear:
        return await client.move_linear(
            pose,
            group=group,
            tcp_speed_mm_s=tcp_speed_mm_s,
            speed_scale=speed_scale,
            accel_scale=accel_scale,
            on_progress=on_progress,
        )
    return await client.move_pose(
        pose,
        group=group,
        speed_scale=speed_scale,
        accel_scale=accel_scale,
        on_progress=on_progress,
    )
