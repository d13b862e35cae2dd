"""``pymotoros urdf``: write a robot model's URDF (base_link → tool0, simple shapes)."""

from __future__ import annotations

from pathlib import Path

import click

from pymotoros.cli.options import BadInput, output_option, robot_option
from pymotoros.errors import ConfigError
from pymotoros.kinematics import urdf_for
from pymotoros.models.robots import robot_model


@click.command()
@robot_option("robot_name")
@output_option("Write the URDF to this file (default: stdout)")
def urdf(robot_name: str, output: Path | None) -> None:
    """Write the URDF of a robot model, for RViz, MoveIt or the web pendant."""
    try:
        text = urdf_for(robot_model(robot_name))
    except ConfigError as exc:
        raise click.BadParameter(str(exc), param_hint="--robot") from None
    if output is None:
        click.echo(text, nl=False)
        return
    try:
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise BadInput(f"-o: cannot write {output}: {exc.strerror}") from None
