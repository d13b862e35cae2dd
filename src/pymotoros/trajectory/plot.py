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
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from pymotoros.models import AxisModel, ControllerModel, RobotModel
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


@dataclass(frozen=True, slots=True)
class Series:
    """One group's samples: times (s, from the trajectory start), positions (T, k) and
    velocities (T, k or None), column ``i`` being the file's joint ``columns[i]``."""

    times: F64Array
    positions: F64Array
    columns: tuple[int, ...]
    velocities: F64Array | None = None

    def column(self, joint: int) -> int | None:
        return self.columns.index(joint) if joint in self.columns else None


@dataclass(frozen=True, slots=True)
class RecordedRun:
    """A run of the trajectory as a session recording shows it.

    ``commanded``: the points the client sent (JOINT_TRAJ_PT_FULL / _EX) at their
    own times, relative to the start point's; ``feedback``: the positions the robot
    reported on the state port (JOINT_FEEDBACK / _EX) at the time they arrived,
    relative to the moment the controller accepted the start point (sequence 0):
    trajectory time 0 on both. One :class:`Series` per group.
    """

    commanded: tuple[Series, ...]
    feedback: tuple[Series, ...]
    source: str = "recording"


LAG_SEARCH_S: Final = (-0.05, 0.5)
"""The time shifts tried for the lag (s): feedback cannot lead the command, but the
arrival time of a state message can trail its sampling by a little; half a second
is far beyond any controller's servo lag (the twin's is 12 ms)."""
LAG_STEP_S: Final = 0.001
"""Resolution of the lag (1 ms: a quarter of the 4 ms interpolation period)."""
LAG_MIN_TRAVEL: Final = 1e-3
"""rad (m): a joint that travels less has no measurable lag (its lag is None)."""


@dataclass(frozen=True, slots=True)
class Tracking:
    """How the feedback followed the command on one joint.

    ``lag_ms``: the time shift that best lays the commanded motion onto the feedback
    (least squares over the samples from the start to the end of the motion plus
    :data:`LAG_SEARCH_S`'s upper end), None for a joint that barely moved;
    ``max_error``/``mean_error``: largest and mean |feedback − command| at the same
    instant, rad (m), over the same samples.
    """

    lag_ms: float | None
    max_error: float
    mean_error: float
    samples: int


def hermite(points_t: F64Array, pos: F64Array, vel: F64Array, t: F64Array) -> F64Array:
    """The cubic through the points with their velocities (as MotoROS interpolates
    between trajectory points), held at the first and last point outside them.
    ``pos``/``vel`` (P,) one joint; returns (len(t),)."""
    t = np.asarray(t, dtype=np.float64)
    if len(points_t) == 1:
        return np.full(t.shape, float(pos[0]))
    k = np.clip(np.searchsorted(points_t, t, side="right") - 1, 0, len(points_t) - 2)
    t0, t1 = points_t[k], points_t[k + 1]
    h = np.where(t1 > t0, t1 - t0, 1.0)
    u = np.clip((t - t0) / h, 0.0, 1.0)
    u2, u3 = u * u, u * u * u
    out: F64Array = (
        (2 * u3 - 3 * u2 + 1) * pos[k]
        + (u3 - 2 * u2 + u) * h * vel[k]
        + (-2 * u3 + 3 * u2) * pos[k + 1]
        + (u3 - u2) * h * vel[k + 1]
    )
    return out


def _commanded_joint(run: RecordedRun, joint: int) -> tuple[F64Array, F64Array, F64Array] | None:
    for series in run.commanded:
        c = series.column(joint)
        if c is not None:
            vel = (
                series.velocities[:, c]
                if series.velocities is not None
                else np.zeros(len(series.times))
            )
            return series.times, series.positions[:, c], vel
    return None


def _feedback_joint(run: RecordedRun, joint: int) -> tuple[F64Array, F64Array] | None:
    for series in run.feedback:
        c = series.column(joint)
        if c is not None:
            return series.times, series.positions[:, c]
    return None


def tracking(run: RecordedRun, joint: int) -> Tracking | None:
    """The lag and tracking error of one file joint; None without command or feedback."""
    cmd = _commanded_joint(run, joint)
    fb = _feedback_joint(run, joint)
    if cmd is None or fb is None:
        return None
    ct, cp, cv = cmd
    ft, fp = fb
    window = (ft >= 0.0) & (ft <= ct[-1] + LAG_SEARCH_S[1])
    ft, fp = ft[window], fp[window]
    if not len(ft):
        return None
    error = np.abs(fp - hermite(ct, cp, cv, ft))
    lag: float | None = None
    if float(np.ptp(cp)) >= LAG_MIN_TRAVEL:
        shifts = np.arange(LAG_SEARCH_S[0], LAG_SEARCH_S[1] + LAG_STEP_S / 2, LAG_STEP_S)
        shifted = hermite(ct, cp, cv, (ft[None, :] - shifts[:, None]).ravel())
        cost = ((shifted.reshape(len(shifts), -1) - fp[None, :]) ** 2).sum(axis=1)
        lag = float(shifts[int(np.argmin(cost))]) * 1000.0
    return Tracking(lag, float(error.max()), float(error.mean()), len(ft))


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


JOINT_LIMITS_LABEL: Final = "joint limits"
VELOCITY_LIMIT_LABEL: Final = "velocity limit"


def limit_lines(ax: Any, limits: Sequence[float], label: str, unit: str) -> None:
    """Dashed lines at the limits that lie within the panel's y range (set before), the
    first of them in the legend; limits off the scale are named in a corner note
    instead, so that the legend never lists a line the panel does not show."""
    lo, hi = ax.get_ylim()
    shown = [v for v in limits if lo <= v <= hi]
    for k, value in enumerate(shown):
        ax.axhline(value, color="red", ls="--", lw=0.8, label=label if k == 0 else None)
    off = [v for v in limits if v not in shown]
    if off:
        values = ", ".join(f"{v:.3g}" for v in off)
        ax.text(
            0.99,
            0.02,
            f"{label} {values} {unit}: off the scale",
            transform=ax.transAxes,
            ha="right",
            va="bottom",
            fontsize=6,
            color="red",
        )


COMMANDED_LABEL: Final = "commanded (points sent)"
FEEDBACK_LABEL: Final = "feedback"
ERROR_LABEL: Final = "feedback − command"


def plot_trajectory(
    traj: Trajectory,
    robot: RobotModel,
    controller: ControllerModel,
    report: CheckReport,
    output: Path,
    *,
    reported: Sequence[Reported] = (),
    run: RecordedRun | None = None,
) -> Any:
    """Draw and save the figure; returns it (tests inspect its axes and lines).

    With ``run`` (from a recording) each position panel also shows the commanded
    points and the feedback, the feedback's legend gives its lag and largest error
    (:func:`tracking`), and a third column shows feedback − command over time.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = traj.joint_names
    axes_models = {a.name: a for g in robot.groups for a in g.axes}
    t_i, p_i, v_i = interpolated(traj, robot, controller, report)
    n = len(names)
    cols = 3 if run is not None else 2
    fig, grid = plt.subplots(
        n, cols, figsize=(5.5 * cols, 1.9 * n + 1.2), sharex=True, squeeze=False
    )
    lags: list[float] = []
    for j, name in enumerate(names):
        row = grid[j]
        lo, hi = _draw_position(row[0], traj, j, t_i, p_i, reported)
        if run is not None:
            lo, hi = _draw_recorded(run, j, _unit(axes_models[name]), row[0], row[2], lo, hi, lags)
        _finish_position(row[0], name, axes_models[name], lo, hi, legend=run is not None)
        _draw_velocity(row[1], traj, j, t_i, v_i, axes_models[name])
    grid[0][0].set_title("position")
    grid[0][1].set_title("velocity")
    for c in range(cols):
        grid[-1][c].set_xlabel("time [s]")
    grid[0][0].legend(loc="best", fontsize=7)
    grid[0][1].legend(loc="best", fontsize=7)
    title = (
        f"{robot.name} on {controller.type.value}: {traj.duration:.3f} s planned, "
        f"{report.duration_s:.3f} s as MotoROS runs it ({report.increments} ticks)"
    )
    if run is not None:
        grid[0][2].set_title("tracking error (feedback − command)")
        if not lags:
            lag = "no lag measured (no joint moved)"
        elif round(min(lags)) == round(max(lags)):
            lag = f"feedback lag {min(lags):.0f} ms"
        else:
            lag = f"feedback lag {min(lags):.0f}..{max(lags):.0f} ms"
        title += f"\n{run.source}: {lag} (t = 0: the start point accepted)"
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(output, dpi=90)
    plt.close(fig)
    return fig


def _unit(axis: AxisModel) -> str:
    return "m" if axis.linear else "rad"


def _draw_position(
    ax: Any,
    traj: Trajectory,
    j: int,
    t_i: F64Array,
    p_i: F64Array,
    reported: Sequence[Reported],
) -> tuple[float, float]:
    """Planned points and MotoROS's interpolation of joint ``j``; returns their range."""
    ax.plot(traj.times, traj.positions[:, j], "o", ms=3, label="planned points")
    ax.plot(t_i, p_i[:, j], "-", lw=1.2, label="MotoROS interpolation")
    for rec in reported:
        ax.plot(rec.times, rec.positions[:, j], "-", lw=1.0, label=rec.label)
    lo = min(float(traj.positions[:, j].min()), float(p_i[:, j].min()))
    hi = max(float(traj.positions[:, j].max()), float(p_i[:, j].max()))
    return lo, hi


def _finish_position(
    ax: Any, name: str, axis: AxisModel, lo: float, hi: float, *, legend: bool
) -> None:
    """The y range (the limits come into view only when the motion comes near them),
    the limit lines within it, the label; with ``legend``, the row's own legend."""
    pad = max(0.1 * (hi - lo), 0.02)
    ax.set_ylim(max(lo - pad, axis.lower - pad), min(hi + pad, axis.upper + pad))
    limit_lines(ax, (axis.lower, axis.upper), JOINT_LIMITS_LABEL, _unit(axis))
    if legend:  # every row: the feedback's legend gives its lag and error
        ax.legend(loc="best", fontsize=6)
    ax.set_ylabel(f"{name}\n[{_unit(axis)}]")


def _draw_velocity(
    ax: Any, traj: Trajectory, j: int, t_i: F64Array, v_i: F64Array, axis: AxisModel
) -> None:
    """Planned and per-tick velocities of joint ``j``, and the velocity limit if in view."""
    ax.plot(traj.times, traj.velocities[:, j], "o", ms=3, label="planned points")
    ax.plot(t_i, v_i[:, j], "-", lw=1.0, label="MotoROS, per tick")
    vmax = axis.max_velocity
    vpeak = max(float(np.abs(v_i[:, j]).max()), float(np.abs(traj.velocities[:, j]).max()))
    span = min(vmax * 1.1, vpeak * 1.2 + 0.05)
    ax.set_ylim(-span, span)
    limit_lines(ax, (-vmax, vmax), VELOCITY_LIMIT_LABEL, f"{_unit(axis)}/s")
    ax.set_ylabel(f"[{_unit(axis)}/s]")


def _draw_recorded(
    run: RecordedRun,
    j: int,
    unit: str,
    ax_p: Any,
    ax_e: Any,
    lo: float,
    hi: float,
    lags: list[float],
) -> tuple[float, float]:
    """The commanded points and the feedback on ``ax_p``, the error on ``ax_e``;
    returns the position range widened to them."""
    cmd = _commanded_joint(run, j)
    fb = _feedback_joint(run, j)
    if cmd is not None:
        ct, cp, _ = cmd
        ax_p.plot(ct, cp, "+", ms=5, color="black", label=COMMANDED_LABEL)
        lo, hi = min(lo, float(cp.min())), max(hi, float(cp.max()))
    track = tracking(run, j)
    if fb is not None:
        ft, fp = fb
        label = FEEDBACK_LABEL
        if track is not None:
            lag = "lag n/a (still)" if track.lag_ms is None else f"lag {track.lag_ms:.0f} ms"
            label += f" ({lag}, max error {track.max_error:.3g} {unit})"
            if track.lag_ms is not None:
                lags.append(track.lag_ms)
        ax_p.plot(ft, fp, "-", lw=1.0, color="tab:green", label=label)
        lo, hi = min(lo, float(fp.min())), max(hi, float(fp.max()))
    if cmd is not None and fb is not None and track is not None:
        ct, cp, cv = cmd
        ft, fp = fb
        error = fp - hermite(ct, cp, cv, ft)
        ax_e.plot(
            ft,
            error,
            "-",
            lw=1.0,
            color="tab:green",
            label=f"{ERROR_LABEL}: mean |e| {track.mean_error:.3g} {unit}, "
            f"max {track.max_error:.3g} {unit}",
        )
        ax_e.axhline(0.0, color="grey", lw=0.6)
    ax_e.set_ylabel(f"[{unit}]")
    if ax_e.lines:
        ax_e.legend(loc="best", fontsize=6)
    return lo, hi
