"""The Cartesian part of the CLI: ``move --pose/--relative`` and the tool they refer to.

Every Cartesian line names the frame its numbers are in and the tool whose TCP it is
about. Poses are in ``base`` (Yaskawa's robot coordinates: ``base_link`` raised by the
S-axis height, 0.275 m on an HC10, from the robot model), while a cell's obstacles are in
``base_link``: a gripper 186 mm above the table reads z -89 mm in base, and without the
frame on screen that looks wrong (issue 29). Tools: the number, name and offset:
MotoROS cannot report the selected tool, so ``--tool N`` (``PYMOTOROS_TOOL``, or
``tool = N`` in the settings file's ``[move]``/``[status]``) says it; a ``pymotoros
tool N`` run earlier is not known to a later process. See :mod:`pymotoros.client.tools`.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Sequence
from typing import Any, Final, Literal, TypeVar

import click

from pymotoros.cli.settings import envvar
from pymotoros.client import RobotClient
from pymotoros.client.streaming import FollowingSample, MoveResult
from pymotoros.client.tools import ToolUnknownError
from pymotoros.errors import PymotorosError
from pymotoros.models.robots import GroupModel
from pymotoros.protocol.constants import MAX_TOOL_NUMBER

_F = TypeVar("_F", bound=Callable[..., Any])

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


def frame_data(group: GroupModel) -> dict[str, Any]:
    """``{"name": "base", "above_base_link_m": h}``: the frame of a pose in JSON output."""
    return {"name": "base", "above_base_link_m": group.base_height}


def frame_note(group: GroupModel) -> str:
    """``in base (0.275 m above base_link, the S-axis height)``: the frame of a printed
    pose, with the height from the robot model (0 for a model whose base is base_link)."""
    if group.base_height == 0.0:
        return "in base (= base_link)"
    return f"in base ({group.base_height:.3f} m above base_link, the S-axis height)"


def pose_text(pose: Sequence[float], *, step: bool = False) -> str:
    """``x 600.0 y 100.0 z 300.0 mm  Rx 180.00 Ry -0.00 Rz 0.00 deg`` (pose in m, rad);
    with ``step`` a relative move's ``dx … drz``."""
    x, y, z, rx, ry, rz = pose
    d = "d" if step else ""
    r = "dr" if step else "R"
    return (
        f"{d}x {x * 1000:.1f} {d}y {y * 1000:.1f} {d}z {z * 1000:.1f} mm"
        f"  {r}x {math.degrees(rx):.2f} {r}y {math.degrees(ry):.2f} {r}z {math.degrees(rz):.2f} deg"
    )


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
    tool: int | None = None,
    avoid: bool = False,
    force: bool = False,
) -> MoveResult:
    """A move to ``pose`` (base coordinates) or by ``relative``; straight with ``linear``.

    With ``tool`` the controller is told first (SELECT_TOOL), so the TCP the plan places
    is the one the controller moves with; without it, the tool must be known otherwise
    (:mod:`pymotoros.client.tools`), else the move is refused before anything moves.
    With a cell that has obstacles the client checks the move against them (``force``
    skips it); ``avoid``: a joint move to ``pose`` around them.
    """
    if tool is not None:
        await client.select_tool(tool, group)
    model = client.robot.groups[group]
    if pose is not None:
        goal = f" to {pose_text(pose)} {frame_note(model)}"
    elif relative is not None:
        axes = "the tool's own axes" if frame == "tool" else frame_note(model)
        goal = f" by {pose_text(relative, step=True)} along {axes}"
    else:
        goal = ""
    click.echo(f"moving the TCP of {client.tools.describe(group)}{goal}", err=True)
    options: dict[str, Any] = {
        "group": group,
        "linear": linear,
        "tcp_speed_mm_s": tcp_speed_mm_s,
        "speed_scale": speed_scale,
        "accel_scale": accel_scale,
        "on_progress": on_progress,
        "force": force,
    }
    if relative is not None:
        result = await client.move_relative(*relative, frame=frame, **options)
    elif pose is None:
        raise click.UsageError("give --pose X Y Z RX RY RZ or --relative KEY=VALUE")
    else:
        result = await client.move_cartesian(pose, avoid=avoid, **options)
    with contextlib.suppress(PymotorosError):  # no feedback: the joint line says it all
        reached = client.tcp_pose(group)
        click.echo(f"the TCP stands at {pose_text(reached)} {frame_note(model)}", err=True)
    return result


# --------------------------------------------------------------------------- the tool


def tool_option(func: _F) -> _F:
    """``--tool N`` (``PYMOTOROS_TOOL``): the tool whose TCP Cartesian lines refer to."""
    return click.option(
        "--tool",
        "tool",
        type=click.IntRange(0, MAX_TOOL_NUMBER),
        default=None,
        envvar=envvar("tool"),
        metavar="N",
        help="The tool in force (0..63): its TCP (from the cell file's tool data) is what "
        "--pose/--relative place and what status reports. MotoROS cannot report the "
        "selected tool: with tools in the cell file, Cartesian moves need this. `move "
        "--pose/--relative` selects it first (SELECT_TOOL); joint moves with a --config "
        "cell that has obstacles check (and --avoid plans) with its shape on the flange.",
    )(func)


def use_tool(client: RobotClient, tool: int | None) -> None:
    """Declare ``tool`` in force on every group (for commands that only read the state)."""
    if tool is not None:
        for index in range(len(client.robot.groups)):
            client.tools.use(tool, group=index)


def tcp_data(client: RobotClient, group: int) -> dict[str, Any]:
    """``{"tcp": pose or None, "tool": {...} or None}`` for ``status --json``."""
    try:
        tool = client.tools.tool(group)
        pose: list[float] | None = list(client.tcp_pose(group))
    except PymotorosError:
        return {"tcp": None, "tool": None, "tcp_frame": frame_data(client.robot.groups[group])}
    return {
        "tcp": pose,
        "tcp_frame": frame_data(client.robot.groups[group]),
        "tool": {
            "number": tool.number,
            "name": tool.name,
            "tcp_m": list(tool.tcp.xyz),
            "rpy_rad": list(tool.tcp.rpy),
        },
    }


def tcp_lines(client: RobotClient, group: int, width: int) -> list[str]:
    """``status``'s TCP line with its frame and the tool it refers to; tool0 and what to do
    when the tool in force is unknown; nothing without feedback or kinematics."""
    label = "TCP"
    try:
        try:
            pose = client.tcp_pose(group)
            tool = client.tools.describe(group)
        except ToolUnknownError:
            pose = client.tcp_pose(group, frame="tool0")
            label = "tool0"
            tool = "TCP unknown: name the tool in force with --tool N"
    except PymotorosError:
        return []
    model = client.robot.groups[group]
    return [
        f"    {label:<{width}}{pose_text(pose)}",
        f"    {'':<{width}}{frame_note(model)}; {tool}",
    ]
