"""How a move shows itself (``move``, ``run``): values in the user's units, the progress
line on a terminal while the robot moves, and the result as JSON."""

from __future__ import annotations

import contextlib
import math
import shutil
import sys
from collections.abc import Callable, Iterator, Sequence
from typing import IO, Any, Final

from pymotoros.client import RobotClient
from pymotoros.client.streaming import FollowingSample, MoveResult

__all__ = ["PROGRESS_REDRAW_S", "move_data", "progress_bar", "progress_line", "to_user", "unit_of"]


def unit_of(deg: bool, linear: bool = False) -> str:
    """The unit the user reads an axis in: m for a linear axis, else rad (deg with --deg)."""
    return "m" if linear else ("deg" if deg else "rad")


def to_user(value: float, deg: bool, linear: bool = False) -> float:
    """An axis value (rad or m) in :func:`unit_of`'s unit."""
    return value if linear or not deg else math.degrees(value)


PROGRESS_REDRAW_S: Final = 0.1
"""Shortest time between two redraws of a terminal's progress line."""


def progress_line(
    label: str,
    sample: FollowingSample,
    positions: Sequence[float],
    *,
    duration_s: float | None,
    deg: bool,
) -> str:
    """``moving  42%  1.3 s left  [0.1234, …] rad``: done, time left and the joints.

    Time left: from the plan when its duration is known (plan time still ahead, plus
    the lag the robot has built up), else extrapolated from the progress so far.
    """
    done = min(max(sample.progress, 0.0), 1.0)
    if duration_s is not None:
        left: float | None = max(0.0, duration_s - (sample.elapsed_s - sample.lag_s))
    elif done > 0.0:
        left = sample.elapsed_s * (1.0 - done) / done
    else:
        left = None
    width = 20
    bar = "#" * round(done * width)
    parts = [f"{label} [{bar:<{width}}] {done * 100:3.0f}%"]
    parts.append("time left ?" if left is None else f"{left:.1f} s left")
    if positions:
        unit = "deg" if deg else "rad"
        parts.append("[" + ", ".join(f"{to_user(p, deg):.3f}" for p in positions) + f"] {unit}")
    return "  ".join(parts)


@contextlib.contextmanager
def progress_bar(
    label: str,
    client: RobotClient | None = None,
    groups: Sequence[int] = (),
    *,
    duration_s: float | None = None,
    deg: bool = False,
    stream: IO[str] | None = None,
) -> Iterator[Callable[[FollowingSample], None]]:
    """A progress line on a terminal's stderr (done, time left, the joints from the
    feedback), fed by the following monitor's samples; nothing when stderr is not a
    terminal. Redrawn in place at most every :data:`PROGRESS_REDRAW_S`."""
    out = sys.stderr if stream is None else stream
    if not out.isatty():
        yield lambda _sample: None
        return
    columns = shutil.get_terminal_size().columns - 1
    last = [-math.inf]

    def progress(sample: FollowingSample) -> None:
        if sample.elapsed_s - last[0] < PROGRESS_REDRAW_S and sample.progress < 1.0:
            return
        last[0] = sample.elapsed_s
        here = (
            [] if client is None else [v for g in groups for v in client.state.positions(g) or ()]
        )
        line = progress_line(label, sample, here, duration_s=duration_s, deg=deg)
        out.write("\r\x1b[K" + line[:columns])
        out.flush()

    try:
        yield progress
    finally:
        out.write("\n")
        out.flush()


def move_data(result: MoveResult) -> dict[str, Any]:
    """A finished move as ``--json`` prints it (``move`` adds the groups' names)."""
    return {
        "positions": list(result.final_positions),
        "elapsed_s": round(result.elapsed_s, 4),
        "planned_s": round(result.trajectory.duration, 4),
        "points": result.stream.points,
        "busy_replies": result.stream.busy_replies,
        "max_lag_s": round(result.following.max_lag_s, 4),
        "slowed": result.following.slowed,
    }
