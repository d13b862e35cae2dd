"""``pymotoros urdf``: write a robot model's URDF (base_link → tool0, simple shapes)."""

from __future__ import annotations

from pathlib import Path

import click

from pymotoros.errors import ConfigError
from pymotoros.kinematics import urdf_for
from pymotoros.models.robots import DEFAULT_ROBOT, ROBOTS, robot_model


@click.command()
@click.option(
    "--robot",
    "robot_name",
    default=DEFAULT_ROBOT,
    show_default=True,
    help=f"Robot model: {', '.join(sorted(ROBOTS))}.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="Write the URDF to this file (default: stdout).",
)
def urdf(robot_name: str, output: Path | None) -> None:
    """Write the URDF of a robot model, for RViz, MoveIt or the web pendant."""
    try:
        text = urdf_for(robot_model(robot_name))
    except ConfigError as exc:
        raise click.BadParameter(str(exc), param_hint="--robot") from None
    if output is None:
        click.echo(text, nl=False)
    else:
        output.write_text(text, encoding="utf-8")
