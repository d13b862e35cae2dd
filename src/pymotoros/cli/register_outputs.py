"""``pymotoros mreg outputs``: the S1CxG register outputs of a cell, decoded.

A controller set up with S1CxG parameters copies its TCP position, TCP speed and each
axis's speed and position into M-registers every interpolation period (seed 003,
Appendix A). ``mreg read`` shows one raw 16-bit word; this command reads every register
the cell's ``[groups.s1cxg]`` table fills and decodes them with the client's own call
(:meth:`pymotoros.client.RobotClient.read_register_outputs`), so the CLI and Python read
the same numbers through one code path.

The command is added to the ``mreg`` group of :mod:`pymotoros.cli.io_commands` here, in
its own module, so that ``pymotoros mreg`` (read, write, outputs) is one group;
``pymotoros.cli.main`` loads ``mreg`` from this module.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Final

import click

from pymotoros.cli.io_commands import mreg
from pymotoros.cli.options import json_option, robot_options
from pymotoros.cli.session import EXIT_CODES_HELP, connected, run, target_from_options
from pymotoros.client import RobotClient
from pymotoros.client.registers import RegisterValues
from pymotoros.errors import ConfigError
from pymotoros.models.cell import read_cell_file
from pymotoros.models.robots import GroupKind, GroupModel
from pymotoros.models.s1cxg import CARTESIAN_NAMES, Quantity, Reading

_WHAT: Final = {
    Quantity.CARTESIAN: "TCP position",
    Quantity.TCP_SPEED: "TCP speed",
    Quantity.AXIS_SPEED: "speed",
    Quantity.AXIS_POSITION: "position",
    Quantity.PULSE_1: "pulse position 1",
    Quantity.PULSE_2: "pulse position 2",
}
_ROBOT_AXES: Final = ("S", "L", "U", "R", "B", "T", "E", "8th")
"""A robot group's axes in controller order (the order of the S1CxG per-axis
parameters); other groups' axes are numbered 1..8."""


def axis_label(group: GroupModel, index: int) -> str:
    """The controller-order axis ``index`` (0..7) as the pendant names it."""
    if group.kind is GroupKind.ROBOT:
        return _ROBOT_AXES[index]
    return f"axis {index + 1}"


def reading_label(group: GroupModel, reading: Reading) -> str:
    """``TCP position X (feedback, base)``, ``S speed (feedback)``, ``TCP speed (command)``."""
    source = reading.source.value
    if reading.quantity is Quantity.CARTESIAN:
        name = CARTESIAN_NAMES[reading.index].capitalize()  # X, Y, Z, Rx, Ry, Rz, Re
        return f"TCP position {name} ({source}, base)"
    if reading.quantity is Quantity.TCP_SPEED:
        return f"TCP speed ({source})"
    return f"{axis_label(group, reading.index)} {_WHAT[reading.quantity]} ({source})"


def outputs_data(
    group_index: int, group: GroupModel, values: RegisterValues, base_height_m: float
) -> dict[str, Any]:
    """``--json``: every decoded output with its unit, raw value and raw unit, and the
    register words read (``{"M010": word}``)."""
    return {
        "group": group_index,
        "group_name": group.name,
        "frame": {"name": "base", "above_base_link_m": base_height_m},
        "outputs": [
            {
                "quantity": r.quantity.value,
                "source": r.source.value,
                "index": r.index,
                "label": reading_label(group, r),
                "value": r.value,
                "unit": r.unit,
                "raw": r.raw,
                "raw_unit": r.raw_unit,
            }
            for r in values.readings
        ],
        "registers": {f"M{n:03d}": w for n, w in sorted(values.words.items())},
    }


def outputs_lines(
    title: str, group: GroupModel, values: RegisterValues, base_height_m: float
) -> list[str]:
    """The human report: one line per output, value in its unit and the raw register
    value beside it, so a number can be checked against the pendant's M-register list."""
    lines = [title]
    if any(r.quantity is Quantity.CARTESIAN for r in values.readings):
        lines.append(
            f"  TCP position in base coordinates: the robot's base frame, {base_height_m:.3f} m "
            "above base_link (the S-axis height)"
        )
    if not values.readings:
        lines.append("  the table configures no output")
        return lines
    width = max(len(reading_label(group, r)) for r in values.readings) + 2
    for r in values.readings:
        raw = f"raw {r.raw} {r.raw_unit}"  # every number with its unit, the raw one too
        lines.append(f"  {reading_label(group, r):<{width}}{r.value:>14.4f} {r.unit:<6}  {raw}")
    words = ", ".join(f"M{n:03d}={w}" for n, w in sorted(values.words.items()))
    lines.append(f"  registers read: {words}")
    return lines


def _check_table(path: Path, group_index: int) -> None:
    """Refuse, before connecting, a cell file without the table to decode with."""
    try:
        data = read_cell_file(path).data
    except ConfigError as exc:
        raise click.BadParameter(str(exc), param_hint="--config") from None
    groups = data.get("groups")
    entry = groups[group_index] if isinstance(groups, list) and group_index < len(groups) else None
    if not isinstance(entry, dict) or not isinstance(entry.get("s1cxg"), dict):
        raise click.BadParameter(
            f"{path.name} has no [groups.s1cxg] table for group {group_index} ([[groups]] "
            f"entry {group_index}): it declares which M-registers the controller fills "
            "(docs/cell.md, examples/cells/hc10_register_outputs.toml); `pymotoros mreg read "
            "N` reads one register raw",
            param_hint="--config",
        )


@mreg.command("outputs", epilog=EXIT_CODES_HELP)
@robot_options
@click.option(
    "--group",
    "group_index",
    type=click.IntRange(0, 3),
    default=0,
    show_default=True,
    help="Control group (its [[groups]] entry's [groups.s1cxg] table).",
)
@json_option("every decoded output with its unit and raw value")
def mreg_outputs(group_index: int, as_json: bool, **kwargs: Any) -> None:
    """Read and decode the S1CxG register outputs of the cell (--config CELL.toml).

    \b
    The [groups.s1cxg] table of the cell file says which M-registers hold what
    (docs/cell.md): TCP position (mm, deg, in base coordinates), TCP speed (mm/s),
    each axis's speed (deg/s) and position (deg), pulse positions. Every register it
    fills is read over the IO port and decoded as robot.read_register_outputs does.
    """
    cell_path: Path | None = kwargs.get("cell_path")
    if cell_path is None:
        raise click.UsageError(
            "mreg outputs needs --config CELL.toml: its [groups.s1cxg] table says which "
            "M-registers hold which value (docs/cell.md)"
        )
    _check_table(cell_path, group_index)
    target = target_from_options(kwargs)

    async def work() -> tuple[RobotClient, RegisterValues]:
        async with connected(target, motion=False, state=False, io=True) as client:
            if group_index >= len(client.robot.groups):
                raise ConfigError(
                    f"--group {group_index}: the cell has {len(client.robot.groups)} group(s)"
                )
            return client, await client.read_register_outputs(cell_path, group_index)

    client, values = run(target, work)
    group = client.robot.groups[group_index]
    height = group.base_height
    if as_json:
        click.echo(json.dumps(outputs_data(group_index, group, values, height)))
        return
    title = (
        f"S1CxG register outputs of group {group_index} ({group.name}) of {cell_path.name}, "
        f"read from {client.host}"
    )
    for line in outputs_lines(title, group, values, height):
        click.echo(line)


__all__ = ["mreg", "mreg_outputs"]
