"""The trajectory plot: per joint, planned and MotoROS-interpolated position and velocity.

One row per joint, two panels: position (rad) and velocity (rad/s). Planned points
(the file) as markers, MotoROS's interpolation (the increments :func:`check_trajectory`
predicts, one per tick) as a line, the joint's limits as dashed lines, and, from a
recording, the positions the robot reported. matplotlib with the Agg backend: no
display needed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from pymotoros.models import ControllerModel, RobotModel
from pymotoros.models.rules import to_pulses
from pymotoros.motion import GroupAxes
from pymotoros.trajectory.check import CheckReport
from pymotoros.trajectory.files import Trajectory

F64Array = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Reported:
    """Positions the robot reported during a run (from a recording): time (s, from the
    first point sent) and positions (T, joints in the file's order)."""

    times: F64Array
    positions: F64Array
    label: str = "feedback"


def interpolated(
    traj: Trajectory, robot: RobotModel, controller: ControllerModel, report: CheckReport
) -> tuple[F64Array, F64Array, F64Array]:
    """(times s, positions, velocities) per tick as MotoROS executes them, file joint order."""
    period = controller.interpolation_period_ms / 1000.0
    ticks = report.increments
    t = np.arange(ticks + 1, dtype=np.float64) * period
    pos = np.zeros((ticks + 1, len(traj.joint_names)))
    vel = np.zeros_like(pos)
    for gi, cols in traj.group_columns(robot):
        group = robot.groups[gi]
        axes = GroupAxes.from_model(group, controller)
        _, inc = report.per_group[group.name]
        start = np.array(axes.take(to_pulses(tuple(traj.positions[0, cols]), axes)))
        path = np.vstack([start, start + np.cumsum(inc, axis=0)]).astype(np.float64)
        steps = np.vstack([np.zeros((1, inc.shape[1])), inc]).astype(np.float64)
        for col, ros in enumerate(axes.columns_list):
            factor = float(axes.factors_ros[ros])
            rows = len(path)
            pos[:rows, cols[ros]] = path[:, col] / factor
            pos[rows:, cols[ros]] = path[-1, col] / factor
            vel[:rows, cols[ros]] = steps[:, col] / factor / period
    return t, pos, vel


def plot_trajectory(
    traj: Trajectory,
    robot: RobotModel,
    controller: ControllerModel,
    report: CheckReport,
    output: Path,
    *,
    reported: Sequence[Reported] = (),
) -> Any:
    """Draw and save the figure; returns it (tests inspect its axes and lines)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = traj.joint_names
    axes_models = {a.name: a for g in robot.groups for a in g.axes}
    t_i, p_i, v_i = interpolated(traj, robot, controller, report)
    n = len(names)
    fig, grid = plt.subplots(n, 2, figsize=(11, 1.9 * n + 1), sharex=True, squeeze=False)
    for j, name in enumerate(names):
        axis = axes_models[name]
        unit = "m" if axis.linear else "rad"
        ax_p, ax_v = grid[j]
        ax_p.plot(traj.times, traj.positions[:, j], "o", ms=3, label="planned points")
        ax_p.plot(t_i, p_i[:, j], "-", lw=1.2, label="MotoROS interpolation")
        for limit in (axis.lower, axis.upper):
            ax_p.axhline(limit, color="red", ls="--", lw=0.8)
        ax_p.lines[-1].set_label("joint limits")
        for rec in reported:
            ax_p.plot(rec.times, rec.positions[:, j], "-", lw=1.0, label=rec.label)
        # keep the limits visible only when the motion comes near them
        lo = min(float(traj.positions[:, j].min()), float(p_i[:, j].min()))
        hi = max(float(traj.positions[:, j].max()), float(p_i[:, j].max()))
        pad = max(0.1 * (hi - lo), 0.02)
        ax_p.set_ylim(max(lo - pad, axis.lower - pad), min(hi + pad, axis.upper + pad))
        ax_p.set_ylabel(f"{name}\n[{unit}]")
        ax_v.plot(traj.times, traj.velocities[:, j], "o", ms=3, label="planned points")
        ax_v.plot(t_i, v_i[:, j], "-", lw=1.0, label="MotoROS, per tick")
        vmax = axis.max_velocity
        ax_v.axhline(vmax, color="red", ls="--", lw=0.8, label="velocity limit")
        ax_v.axhline(-vmax, color="red", ls="--", lw=0.8)
        vpeak = max(float(np.abs(v_i[:, j]).max()), float(np.abs(traj.velocities[:, j]).max()))
        ax_v.set_ylim(-min(vmax * 1.1, vpeak * 1.2 + 0.05), min(vmax * 1.1, vpeak * 1.2 + 0.05))
        ax_v.set_ylabel(f"[{unit}/s]")
    grid[0, 0].set_title("position")
    grid[0, 1].set_title("velocity")
    grid[-1, 0].set_xlabel("time [s]")
    grid[-1, 1].set_xlabel("time [s]")
    grid[0, 0].legend(loc="best", fontsize=7)
    grid[0, 1].legend(loc="best", fontsize=7)
    fig.suptitle(
        f"{robot.name} on {controller.type.value}: {traj.duration:.3f} s planned, "
        f"{report.duration_s:.3f} s as MotoROS runs it ({report.increments} ticks)"
    )
    fig.tight_layout()
    fig.savefig(output, dpi=90)
    plt.close(fig)
    return fig
