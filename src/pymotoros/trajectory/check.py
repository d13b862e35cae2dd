"""The pre-flight: what MotoROS 1.9.12 will do with a trajectory, and what it never checks.

MotoROS's own validation and interpolation run offline on the engine the twin uses
(:func:`pymotoros.motion.interpolate_arrays` and the checks of
:mod:`pymotoros.models.rules`), so a refusal here is the refusal the controller
sends. Then the increments it would queue are checked against the model for what
MotoROS never checks: joint limits between points (the cubic can overshoot), per-tick
increments above an axis's maximum, per-tick acceleration, points closer than one
tick (MotoROS takes at most one point per group per tick), dropped points, and the
start margin against a given current position.

A warning needs a real excess: whole-pulse rounding alone moves a position by up to
one pulse and an acceleration by up to two pulses per tick²; those are allowed.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from pymotoros.errors import TrajectoryRejectedError
from pymotoros.models import ControllerModel, FloatMode, GroupModel, RobotModel
from pymotoros.models.cell import CellModels
from pymotoros.models.fsu import fsu_joint_clip
from pymotoros.models.rules import START_TOLERANCE_PULSES, check_start
from pymotoros.models.rules import TrajPoint as RulesPoint
from pymotoros.motion import GroupAxes, interpolate_arrays, to_pulses
from pymotoros.motion.numerics import c_int_array
from pymotoros.protocol.constants import InvalidSubcode
from pymotoros.trajectory.collisions import Collision
from pymotoros.trajectory.files import Trajectory

I64Array = npt.NDArray[np.int64]

logger = logging.getLogger(__name__)

POSITION_ROUNDING_PULSES: Final = 1
"""A position computed from whole pulses is off by at most one pulse (truncation)."""
ACCEL_ROUNDING_PULSES: Final = 2
"""Two neighbouring increments each rounded by up to one pulse: their difference (the
per-tick acceleration) by up to two."""

EXIT_OK: Final = 0
EXIT_REFUSED: Final = 1
EXIT_WARNINGS: Final = 4

_REMEDIES: Final[dict[int, str]] = {
    int(InvalidSubcode.DATA_START_POS): (
        "start the trajectory where the robot is (read it with `pymotoros status`), or "
        "move there first with `pymotoros move`"
    ),
    int(InvalidSubcode.DATA_SPEED): (
        "re-time the trajectory slower (lower velocity scaling) so that every velocity "
        "stays below the axis maximum"
    ),
    int(InvalidSubcode.DATA_TIME): "split the trajectory: point times must stay below 4 h",
}


@dataclass(frozen=True, slots=True)
class Refused:
    """The first point MotoROS would refuse (the ``refusal`` of ``--json``)."""

    point: int
    axis: str | None
    value: float
    limit: float
    result: int
    subcode: int
    meaning: str
    remedy: str
    group: str = ""
    message: str = ""


@dataclass(frozen=True, slots=True)
class Warning_:  # noqa: N801 - "Warning" is a builtin
    """Something MotoROS accepts but the robot should not do."""

    kind: str
    """position | increment | acceleration | feed | dropped | start | fsu"""
    point: int
    axis: str | None
    value: float
    limit: float
    text: str


@dataclass(slots=True)
class CheckReport:
    """The outcome; :meth:`to_json` is the ``pymotoros check --json`` contract."""

    accepted: bool
    refusal: Refused | None
    warnings: list[Warning_] = field(default_factory=list)
    duration_s: float = 0.0
    increments: int = 0
    start_margin_pulses: int | None = None
    max_jerk_ratio: float = 0.0
    """Largest per-tick jerk as a fraction of the model's limit (informational: the
    cubic's acceleration steps at every point, so MotoROS's own motion exceeds it)."""
    per_group: dict[str, tuple[I64Array, I64Array]] = field(default_factory=dict, repr=False)
    """Group name → (time_ms, increments) per tick as MotoROS executes them: its queue
    entries, a partial step joined with the next as IncMove joins them (:func:`per_tick`)."""
    collisions: list[Collision] = field(default_factory=list)
    """Contacts with the cell's obstacles or itself along the motion (``--config`` with a
    ``[workspace]``, trajectory/collisions.py): a crash, so the exit code is 1."""

    @property
    def exit_code(self) -> int:
        """The exit status of ``pymotoros check``: 0 accepted, 4 accepted with warnings, 1 refused
        or colliding."""
        if not self.accepted or self.collisions:
            return EXIT_REFUSED
        return EXIT_WARNINGS if self.warnings else EXIT_OK

    def to_json(self) -> dict[str, Any]:
        """The report as plain JSON values: what ``pymotoros check --json`` prints."""
        refusal = None
        if self.refusal is not None:
            r = asdict(self.refusal)
            refusal = {
                k: r[k]
                for k in (
                    "point",
                    "axis",
                    "value",
                    "limit",
                    "result",
                    "subcode",
                    "meaning",
                    "remedy",
                )
            }
        return {
            "accepted": self.accepted,
            "refusal": refusal,
            "warnings": [{k: v for k, v in asdict(w).items()} for w in self.warnings],
            "duration_s": self.duration_s,
            "increments": self.increments,
            "start_margin_pulses": self.start_margin_pulses,
            "collisions": [c.to_json() for c in self.collisions],
        }


def check_against_cell(
    traj: Trajectory, cell: CellModels, *, current: Sequence[float] | None = None
) -> CheckReport:
    """:func:`check_trajectory` against a cell file's models (``pymotoros check
    --config``): its controller, its groups, and its FSU joint-speed limit."""
    return check_trajectory(
        traj,
        cell.robot,
        cell.controller,
        current=current,
        fsu_speed_limit_pct=cell.fsu_speed_limit_pct,
    )


def _refused(exc: TrajectoryRejectedError, axes: GroupAxes) -> Refused:
    from pymotoros.protocol.constants import ResultCode

    sub = InvalidSubcode(exc.subcode)
    axis: str | None = None
    if exc.axis is not None:
        if sub is InvalidSubcode.DATA_START_POS:
            axis = axes.joint_at_slot(exc.axis)
        else:
            axis = axes.joint_name(exc.axis)
    return Refused(
        point=exc.point,
        axis=axis,
        value=float(exc.value if exc.value is not None else 0.0),
        limit=float(exc.limit if exc.limit is not None else 0.0),
        result=int(ResultCode.INVALID),
        subcode=int(sub),
        meaning=sub.meaning,
        remedy=_REMEDIES.get(int(sub), "fix the point"),
        group=axes.name,
        message=str(exc),
    )


def check_trajectory(
    traj: Trajectory,
    robot: RobotModel,
    controller: ControllerModel,
    *,
    current: Sequence[float] | None = None,
    fsu_speed_limit_pct: int | None = None,
) -> CheckReport:
    """Check ``traj`` for ``robot`` on ``controller``; ``current`` is the robot's
    position (all joints of the groups the file names, file order), default the start.

    ``fsu_speed_limit_pct``: the controller's FSU joint-speed limit (a cell file's
    ``controller.fsu_speed_limit_pct``, :func:`check_against_cell`): the increments are
    then the ones the FSU lets through, tick by tick, with MotoROS resending what it
    dropped, and a ``fsu`` warning says how much longer the motion takes.
    """
    columns = traj.group_columns(robot)
    if not columns:
        raise TrajectoryRejectedError(
            f"the trajectory names none of {robot.name}'s groups", point=0, subcode=0
        )
    cur = None if current is None else np.asarray(current, dtype=np.float64)
    if cur is not None and cur.shape != (len(traj.joint_names),):
        raise ValueError(
            f"--from needs {len(traj.joint_names)} values (the file's joints), got {cur.shape}"
        )
    first: Refused | None = None
    report = CheckReport(accepted=True, refusal=None)
    checked_axes: dict[str, GroupAxes] = {}
    margins: list[int] = []
    for gi, cols in columns:
        group = robot.groups[gi]
        axes = GroupAxes.from_model(group, controller)
        pos = traj.positions[:, cols]
        vel = traj.velocities[:, cols]
        if cur is not None:
            commanded = to_pulses(tuple(cur[cols].tolist()), axes)
            start = RulesPoint(float(traj.times[0]), tuple(pos[0].tolist()), tuple(vel[0].tolist()))
            requested = to_pulses(start.pos, axes)
            margins.append(
                START_TOLERANCE_PULSES
                - max(abs(a - b) for a, b in zip(requested, commanded, strict=True))
            )
            refusal = check_start(start, commanded, axes)
            if refusal is not None:
                exc = refusal.error(0)
                cand = _refused(exc, axes)
                if first is None or cand.point < first.point:
                    first = cand
                continue
        try:
            entry_ms, entries = interpolate_arrays(traj.times, pos, vel, axes)
        except TrajectoryRejectedError as exc:
            cand = _refused(exc, axes)
            if first is None or cand.point < first.point:
                first = cand
            continue
        time_ms, inc = per_tick(entry_ms, entries, _point0_ms(traj, controller), axes.period_ms)
        report.per_group[group.name] = (time_ms, inc)
        report.warnings.extend(_model_checks(traj, pos, axes, time_ms, inc, report, group))
        checked_axes[group.name] = axes
    if margins:
        report.start_margin_pulses = min(margins)
    if first is not None:
        report.accepted = False
        report.refusal = first
        report.warnings.clear()
        report.per_group.clear()
        return report
    period = controller.interpolation_period_ms
    if fsu_speed_limit_pct is not None:
        report.warnings.extend(_fsu(traj, report, checked_axes, fsu_speed_limit_pct, period))
    ticks = max((len(t) for t, _ in report.per_group.values()), default=0)
    report.increments = ticks
    report.duration_s = ticks * period / 1000.0
    report.warnings.extend(_feed_checks(traj, period, controller.float_mode))
    report.warnings.sort(key=lambda w: (w.point, w.kind))
    return report


def fsu_clip(axes: GroupAxes, pct: int) -> tuple[int, ...]:
    """Per slot, the most pulses an FSU joint-speed limit of ``pct`` % lets the
    controller execute in one tick: that share of the axis's maximum increment, at
    least one pulse (the twin's :class:`~pymotoros.controller.safety.fsu.FsuFunction`)."""
    return fsu_joint_clip(axes.max_increment, pct)


def fsu_execution(groups: Sequence[tuple[GroupAxes, I64Array]], pct: int) -> list[I64Array]:
    """Per group, the increments the servos execute tick by tick under an FSU
    joint-speed limit of ``pct`` %, from the increments IncMove sends (:func:`per_tick`).

    The FSU executes at most :func:`fsu_clip` pulses per axis and tick and drops the
    rest; MotoROS 1.9.12 sees the shortfall in the commanded position, resends the
    missing pulses (clamped to what the controller took the tick before, or the axis
    maximum where it took nothing) and reads no queue entry of any group until every
    group's pulses are through (reference §5.6 step 3). The motion ends where it
    would have, later.
    """
    cols = [list(axes.axis_slots) for axes, _ in groups]
    clips = [[fsu_clip(axes, pct)[s] for s in c] for (axes, _), c in zip(groups, cols, strict=True)]
    maxes = [[axes.max_increment[s] for s in c] for (axes, _), c in zip(groups, cols, strict=True)]
    length = max((len(inc) for _, inc in groups), default=0)
    padded = [
        np.vstack([inc, np.zeros((length - len(inc), len(c)), dtype=np.int64)])
        for (_, inc), c in zip(groups, cols, strict=True)
    ]
    # rows the FSU clips in some group: between them every pulse goes through as sent
    clipped = np.zeros(length, dtype=bool)
    for rows_g, clip_g in zip(padded, clips, strict=True):
        clipped |= np.any(np.abs(rows_g) > np.array(clip_g, dtype=np.int64), axis=1)
    clipped_at = np.flatnonzero(clipped).tolist()
    zero = [[0] * len(c) for c in cols]
    to_process = [list(z) for z in zero]
    processed = [list(z) for z in zero]
    chunks: list[list[I64Array]] = [[] for _ in groups]
    ticks: list[list[list[int]]] = [[] for _ in groups]  # since the last chunk

    def flush() -> None:
        for g, c in enumerate(cols):
            if ticks[g]:
                chunks[g].append(np.array(ticks[g], dtype=np.int64).reshape(-1, len(c)))
                ticks[g] = []

    missing = False
    k = 0
    nxt = 0  # index into clipped_at
    while missing or k < length:
        if not missing:
            while nxt < len(clipped_at) and clipped_at[nxt] < k:
                nxt += 1
            stop = clipped_at[nxt] if nxt < len(clipped_at) else length
            if stop > k:  # nothing clipped before ``stop``: executed as sent
                flush()
                for g in range(len(groups)):
                    chunks[g].append(padded[g][k:stop])
                k = stop
                continue
            sends = [p[k].tolist() for p in padded]
            to_process = [list(x) for x in sends]
            k += 1
        else:
            sends = []
            for g in range(len(groups)):
                rest = [a - b for a, b in zip(to_process[g], processed[g], strict=True)]
                clamp = [abs(t) or m for t, m in zip(processed[g], maxes[g], strict=True)]
                sends.append([max(-c, min(c, r)) for r, c in zip(rest, clamp, strict=True)])
                to_process[g] = rest
        missing = False
        for g, send in enumerate(sends):
            done = [max(-c, min(c, x)) for x, c in zip(send, clips[g], strict=True)]
            processed[g] = done
            ticks[g].append(done)
            missing = missing or done != to_process[g]
    flush()
    return [
        np.vstack(parts).astype(np.int64) if parts else np.zeros((0, len(c)), dtype=np.int64)
        for c, parts in zip(cols, chunks, strict=True)
    ]


def _fsu(
    traj: Trajectory,
    report: CheckReport,
    axes_of: dict[str, GroupAxes],
    pct: int,
    period_ms: int,
) -> list[Warning_]:
    """Replace the increments by what the FSU lets through; warn where it clips."""
    names = list(report.per_group)
    if not names:
        return []
    before = max(len(t) for t, _ in report.per_group.values())
    groups = [(axes_of[n], report.per_group[n][1]) for n in names]
    executed = fsu_execution(groups, pct)
    first: tuple[int, int, str, float, float] | None = None  # (tick, point, axis, value, clip)
    point_ms = np.asarray(traj.times, dtype=np.float64) * 1000.0
    for name, (axes, inc) in zip(names, groups, strict=True):
        time_ms = report.per_group[name][0]
        clip = np.array([fsu_clip(axes, pct)[s] for s in axes.axis_slots], dtype=np.int64)
        over = np.abs(inc) > clip
        if over.any():
            k = int(np.argmax(over.any(axis=1)))
            col = int(np.argmax(over[k]))
            if first is None or k < first[0]:
                ros = axes.columns_list[col]
                first = (
                    k,
                    _point_of(time_ms, point_ms, k),
                    axes.joint_names[ros],
                    float(np.abs(inc[:, col]).max()),
                    float(clip[col]),
                )
    for name, done in zip(names, executed, strict=True):
        time_ms = report.per_group[name][0]
        t0 = int(time_ms[0]) if len(time_ms) else period_ms
        ticks = t0 + period_ms * np.arange(len(done), dtype=np.int64)  # one entry a tick
        report.per_group[name] = (ticks, done)
    if first is None:
        return []
    after = max(len(d) for d in executed)
    _, point, axis, value, limit = first
    return [
        Warning_(
            "fsu",
            point,
            axis,
            value,
            limit,
            f"the cell's FSU joint-speed limit ({pct} %) lets {axis} move at most "
            f"{int(limit)} pulses per {period_ms} ms tick; the trajectory asks up to "
            f"{int(value)}: the FSU drops the rest, MotoROS resends it, and the motion takes "
            f"{after * period_ms / 1000:.3f} s instead of {before * period_ms / 1000:.3f} s "
            f"(behind the trajectory's times); re-time it to at most {pct} % of the axis "
            "speeds or raise the FSU limit",
        )
    ]


def _point0_ms(traj: Trajectory, controller: ControllerModel) -> int:
    """The start point's time as MotoROS holds it (integer ms of the float32 time)."""
    t32 = np.asarray(traj.times[:1], dtype=np.float32)
    if controller.float_mode is FloatMode.X87_EXTENDED:
        exact = t32.astype(np.float64) * 1000.0
    else:
        exact = (t32 * np.float32(1000.0)).astype(np.float64)
    return int(c_int_array(exact, controller.float_mode)[0])


def per_tick(
    entry_ms: I64Array, entries: I64Array, start_ms: int, period_ms: int
) -> tuple[I64Array, I64Array]:
    """The queue entries as IncMove executes them: one tick each, except that an entry
    is joined with the following ones that end within one period of the time the
    previous tick reached (a segment's partial last step and the next segment's first
    step move in one tick, reference §5.6; :func:`pymotoros.motion.incmove.inc_move`).

    ``start_ms`` is the start point's time (where the first tick starts from). Returns
    (time reached, increments) per tick: the motion's length is the number of rows.
    """
    n = len(entry_ms)
    if n == 0:
        return entry_ms, entries
    gaps = np.diff(entry_ms, prepend=start_ms)
    if not np.any(gaps[1:] + gaps[:-1] <= period_ms):
        return entry_ms, entries  # no two entries end within one period: nothing joins
    times = entry_ms.tolist()
    keep: list[int] = []  # the index of each tick's last entry
    q_time = start_ms
    i = 0
    while i < n:
        limit = q_time + period_ms
        j = i
        while j + 1 < n and q_time <= times[j + 1] <= limit:
            j += 1
        keep.append(j)
        q_time = times[j]
        i = j + 1
    last = np.asarray(keep, dtype=np.intp)
    first = np.concatenate(([0], last[:-1] + 1))
    return entry_ms[last], np.add.reduceat(entries, first, axis=0).astype(np.int64)


def _point_of(time_ms: I64Array, point_ms: npt.NDArray[np.float64], k: int) -> int:
    """The point whose segment holds queue entry ``k`` (the segment's end point)."""
    return int(min(np.searchsorted(point_ms, time_ms[k], side="left"), len(point_ms) - 1))


def _model_checks(
    traj: Trajectory,
    pos: npt.NDArray[np.float64],
    axes: GroupAxes,
    time_ms: I64Array,
    inc: I64Array,
    report: CheckReport,
    group_model: GroupModel,
) -> list[Warning_]:
    group = axes.name
    out: list[Warning_] = []
    if not len(inc):
        return out
    point_ms = np.asarray(traj.times, dtype=np.float64) * 1000.0
    models = {a.name: a for a in group_model.axes}
    t = axes.period_ms / 1000.0
    start = np.array(axes.take(to_pulses(tuple(pos[0].tolist()), axes)), dtype=np.int64)
    path = start + np.cumsum(inc, axis=0)
    for col, ros in enumerate(axes.columns_list):
        name = axes.joint_names[ros]
        axis = models[name]
        factor = float(axes.factors_ros[ros])
        slot = axes.axis_slots[col]
        u = "m" if axis.linear else "rad"  # every number with its unit
        # positions between points
        lo = axis.lower * factor - POSITION_ROUNDING_PULSES
        hi = axis.upper * factor + POSITION_ROUNDING_PULSES
        p = path[:, col]
        beyond = (p < lo) | (p > hi)
        if beyond.any():
            k = int(np.argmax(beyond))
            value = float(p[k]) / factor
            limit = axis.lower if value < axis.lower else axis.upper
            worst = float(p.max() if value > axis.upper else p.min()) / factor
            out.append(
                Warning_(
                    "position",
                    _point_of(time_ms, point_ms, k),
                    name,
                    worst,
                    limit,
                    f"{group} {name} reaches {worst:.6g} {u} at {time_ms[k]} ms, beyond its "
                    f"limit {limit:.6g} {u} (MotoROS checks no joint limits; the controller's "
                    "soft limits stop the robot with an alarm); add points or slow down there",
                )
            )
        # increments above maxInc
        mx = axes.max_increment[slot]
        big = np.abs(inc[:, col]) > mx
        if big.any():
            k = int(np.argmax(big))
            out.append(
                Warning_(
                    "increment",
                    _point_of(time_ms, point_ms, k),
                    name,
                    float(abs(inc[k, col])),
                    float(mx),
                    f"{group} {name} moves {abs(int(inc[k, col]))} pulses in one "
                    f"{axes.period_ms} ms "
                    f"tick at {time_ms[k]} ms; its maximum is {mx} pulses per tick; slow down",
                )
            )
        # acceleration and jerk per tick, robot at rest before and after
        v = np.concatenate(([0], inc[:, col], [0])).astype(np.float64)
        d2 = np.diff(v)
        amax = axis.max_acceleration
        accel = np.abs(d2) / (factor * t * t)
        allow = amax + ACCEL_ROUNDING_PULSES / (factor * t * t)
        over = accel > allow
        if over.any():
            k = min(int(np.argmax(over)), len(time_ms) - 1)
            out.append(
                Warning_(
                    "acceleration",
                    _point_of(time_ms, point_ms, k),
                    name,
                    float(accel.max()),
                    amax,
                    f"{group} {name} accelerates at up to {accel.max():.6g} {u}/s² (first at "
                    f"{time_ms[k]} ms), above its {amax:.6g} {u}/s² (plus {allow - amax:.3g} "
                    f"{u}/s² for whole-pulse rounding); re-time with lower acceleration scaling",
                )
            )
        if len(d2) > 1 and axis.max_jerk > 0:
            jerk = np.abs(np.diff(d2)) / (factor * t**3)
            report.max_jerk_ratio = max(report.max_jerk_ratio, float(jerk.max() / axis.max_jerk))
    # the points themselves
    for col, name in enumerate(axes.joint_names):
        axis = models[name]
        u = "m" if axis.linear else "rad"
        bad = (pos[:, col] < axis.lower) | (pos[:, col] > axis.upper)
        if bad.any():
            i = int(np.argmax(bad))
            value = float(pos[i, col])
            limit = axis.lower if value < axis.lower else axis.upper
            out.append(
                Warning_(
                    "position",
                    i,
                    name,
                    value,
                    limit,
                    f"point {i}: {group} {name} = {value:.6g} {u} is beyond its limit "
                    f"{limit:.6g} {u}",
                )
            )
    return out


def _short_gap_cause(
    traj: Trajectory, exact: np.ndarray, ms: np.ndarray, i: int, period_ms: int
) -> str:
    """Why the gap after point ``i`` is short, and what to do.

    MotoROS turns a point's float32 time into whole milliseconds by truncation
    (reference §3.4 step 5.2 and §11: ms = trunc(float32(time) × 1000)). Times on an
    exact tick grid are often a hair below it as float32 (0.02 s is 0.0199999996 s),
    so a file sampled at exactly one tick loses a millisecond now and then and the gap
    it meant as 4 ms reaches MotoROS as 3 ms. The user sees that only if the message
    says so; otherwise a 4 ms file "with 3 ms gaps" reads as a bug in the check.
    """
    meant_ms = round((float(traj.times[i + 1]) - float(traj.times[i])) * 1000.0, 6)
    if meant_ms < period_ms:
        return (
            f"the file itself spaces them {meant_ms:g} ms apart; sample it at "
            f"{period_ms} ms or more. "
        )
    return (
        f"the file spaces them {meant_ms:g} ms apart, but MotoROS truncates each point's "
        "float32 time to whole milliseconds (reference §3.4 step 5.2, §11: "
        f"ms = trunc(float32(time) × 1000)): point {i + 1} at {float(traj.times[i + 1]):.9g} s "
        f"is {float(exact[i + 1]):.7f} ms as float32, truncated to {ms[i + 1]:g} ms, "
        f"point {i} at {float(traj.times[i]):.9g} s to {ms[i]:g} ms, so "
        f"{float(exact[i + 1] - exact[i]):.7g} ms is truncated to {ms[i + 1] - ms[i]:g} ms; "
        "put every time half a millisecond past its tick (add 0.0005 s to each time) or "
        f"sample at {period_ms + 1} ms or more. "
    )


def _feed_checks(traj: Trajectory, period_ms: int, mode: FloatMode) -> list[Warning_]:
    """Point times as MotoROS sees them (integer ms of the float32 time, §11)."""
    out: list[Warning_] = []
    t32 = np.asarray(traj.times, dtype=np.float32)
    if mode is FloatMode.X87_EXTENDED:
        exact = t32.astype(np.float64) * 1000.0  # exact: 24 × 10 bits
    else:
        exact = (t32 * np.float32(1000.0)).astype(np.float64)
    ms = c_int_array(exact, mode).astype(np.float64)
    gaps = np.diff(ms)
    for i in np.flatnonzero(gaps <= 0)[:1]:
        out.append(
            Warning_(
                "dropped",
                int(i) + 1,
                None,
                float(gaps[i]),
                0.0,
                f"point {i + 1} is not after point {i} ({gaps[i]:g} ms); MotoROS accepts it and "
                "drops it without moving",
            )
        )
    short = (gaps > 0) & (gaps < period_ms)
    if short.any():
        i = int(np.argmax(short))
        out.append(
            Warning_(
                "feed",
                i + 1,
                None,
                float(gaps[i]),
                float(period_ms),
                f"{int(short.sum())} point(s) follow the one before by less than one "
                f"{period_ms} ms tick (first: point {i + 1}, {gaps[i]:g} ms after point {i}); "
                + _short_gap_cause(traj, exact, ms, i, period_ms)
                + "MotoROS takes at most "
                "one point per group per tick, so the motion falls behind the trajectory's times",
            )
        )
    return out
