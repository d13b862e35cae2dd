"""What the user asked ``pymotoros move`` for, checked against the robot model before
anything is sent: one target given in a way that fits it (usage errors, exit 2), its
groups, and the joint goal in rad/m with each value's count, finiteness and limits
checked (exit 2 with what to give instead).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import click

from pymotoros.cli.cartesian import parse_relative, pose_from_args
from pymotoros.cli.move_report import to_user, unit_of
from pymotoros.cli.session import InputError, Target
from pymotoros.client import RobotClient
from pymotoros.client.srdf import NamedPoseError
from pymotoros.models import GroupModel
from pymotoros.models.cell import CellModels, load_cell_models

__all__ = ["MoveGoal", "MoveRequest", "need_obstacles", "resolve_goal"]


@dataclass(frozen=True, slots=True)
class MoveRequest:
    """What the user asked ``move`` for, as typed (checked by :meth:`check_usage`)."""

    joints: tuple[float, ...]
    name: str | None
    srdf: Path | None
    deg: bool
    speed_scale: float
    accel_scale: float
    group: tuple[str, ...]
    enable_first: bool
    as_json: bool
    as_pose: bool = False
    linear: bool = False
    relative: tuple[str, ...] = ()
    frame: str = "base"
    tcp_speed_mm_s: float = 250.0
    tool: int | None = None
    force: bool = False
    avoid: bool = False

    @property
    def cartesian(self) -> bool:
        return self.as_pose or bool(self.relative)

    def check_usage(self) -> None:
        """One target, given in a way that fits it (usage errors, exit 2)."""
        if self.linear and not self.as_pose:
            raise click.UsageError(
                "--linear goes with --pose (--relative moves are always straight)"
            )
        if self.as_pose and (self.relative or self.name is not None):
            raise click.UsageError("give one target: --pose, --relative or --named")
        if self.relative and self.joints:
            raise click.UsageError("--relative takes no positional values")
        if not self.cartesian and (self.name is None) == (not self.joints):
            raise click.UsageError("give either joint values J1 ... Jn or --named NAME")
        if self.srdf is not None and self.name is None:
            raise click.UsageError("--srdf goes with --named")
        if self.avoid and (self.linear or self.relative):
            raise click.UsageError(
                "--avoid plans a joint move around the obstacles (J1 ... Jn, --named or "
                "--pose without --linear); a straight line (--linear, --relative) cannot "
                "go around them"
            )


@dataclass(frozen=True, slots=True)
class MoveGoal:
    """The checked target of a move: its groups, their models, and the joint goal (a
    Cartesian move's goal is planned by the client: ``goal`` is empty)."""

    groups: tuple[int, ...]
    models: list[GroupModel]
    goal: tuple[float, ...]
    pose: tuple[float, ...] | None = None
    relative: tuple[float, ...] | None = None


def resolve_goal(target: Target, req: MoveRequest) -> MoveGoal:
    """The goal checked against the robot model before anything is sent."""
    client = target.client()
    given = tuple(client.group_index(g) for g in req.group)
    if len(set(given)) != len(given):
        raise InputError("a --group is given twice: give each group once")
    if req.cartesian:
        if len(given) > 1:
            raise InputError("a Cartesian move (--pose, --relative) takes one --group")
        groups = given or (0,)
        rel = parse_relative(req.relative, req.deg) if req.relative else None
        pose = pose_from_args(req.joints, req.deg) if req.as_pose else None
        return MoveGoal(groups, [client.robot.groups[groups[0]]], (), pose, rel)
    if req.name is not None:
        groups, goal = _named_groups(client, req.name, req.srdf, given)
    else:
        groups = given or (0,)
        goal = _goal_from_values(req.joints, [client.robot.groups[g] for g in groups], req.deg)
    return MoveGoal(groups, [client.robot.groups[g] for g in groups], goal)


def _named_groups(
    client: RobotClient, name: str, srdf: Path | None, given: tuple[int, ...]
) -> tuple[tuple[int, ...], tuple[float, ...]]:
    """The groups a named pose moves and its goal: the groups given with --group, else
    every group of the robot the pose sets (the built-in home sets them all)."""
    if given:
        return given, tuple(v for g in given for v in client.named_pose(name, srdf=srdf, group=g))
    groups: list[int] = []
    goal: list[float] = []
    first_error: NamedPoseError | None = None
    for index in range(len(client.robot.groups)):
        try:
            values = client.named_pose(name, srdf=srdf, group=index)
        except NamedPoseError as exc:
            first_error = first_error or exc
            continue
        groups.append(index)
        goal.extend(values)
    if not groups:
        assert first_error is not None  # noqa: S101 - a robot has at least one group
        raise first_error
    return tuple(groups), tuple(goal)


def _goal_from_values(
    values: tuple[float, ...], models: list[GroupModel], deg: bool
) -> tuple[float, ...]:
    """The goal in rad/m from the user's values, each checked: count, NaN, limits."""
    axes = [a for m in models for a in m.axes]
    if len(values) != len(axes):
        needs = "; ".join(f"{m.name}: {m.num_axes} ({', '.join(m.joint_names)})" for m in models)
        raise InputError(
            f"{len(values)} values given, {len(axes)} needed ({needs}); "
            "repeat --group to move several groups"
        )
    goal = []
    for value, axis in zip(values, axes, strict=True):
        u = unit_of(deg, axis.linear)
        if not math.isfinite(value):
            raise InputError(f"{axis.name}: {value} is not a number; give a finite value in {u}")
        v = value if axis.linear or not deg else math.radians(value)
        if not axis.lower <= v <= axis.upper:
            lo, hi = to_user(axis.lower, deg, axis.linear), to_user(axis.upper, deg, axis.linear)
            raise InputError(
                f"{axis.name}: {value:g} {u} is outside its limits "
                f"[{lo:.4g}, {hi:.4g}] {u}; give a value within them"
                + ("" if deg or axis.linear else " (values in degrees need --deg)")
            )
        goal.append(v)
    return tuple(goal)


def need_obstacles(cell: Path | CellModels | None) -> None:
    """``--avoid`` plans around the obstacles of the --config cell: without them it
    would silently plan a plain move (usage error, exit 2)."""
    models = None
    if cell is not None:
        models = cell if isinstance(cell, CellModels) else load_cell_models(cell)
    if models is None or not models.workspace.obstacles:
        raise click.UsageError(
            "--avoid needs --config CELL.toml whose [workspace] has obstacles: the cell "
            "file names them (the controller cannot report them)"
        )
