"""One trajectory model, three file formats.

* CSV: exactly what ``pymotoros interpolate`` reads (header, then
  ``time,p1..pn,v1..vn``); single group, joints in the robot's ROS order.
* JSON (schema in ``docs/trajectories.md``)::

      {"format": "pymotoros-trajectory", "version": 1,
       "robot": "hc10" | null, "controller": "yrc1000" | null,
       "joint_names": [...],
       "points": [{"time": s, "positions": [...], "velocities": [...]}, ...]}

* YAML: a ``trajectory_msgs/JointTrajectory`` as ``rostopic echo`` (ROS 1:
  ``time_from_start: {secs, nsecs}``) or ``ros2 topic echo`` (ROS 2:
  ``{sec, nanosec}``) print it, one message, optionally followed by ``---``.

Multi-group trajectories (SDA10F) share one time line and name the joints of every
group, as MoveIt plans them; :meth:`Trajectory.group_columns` splits them per group.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
import numpy.typing as npt
import yaml

from pymotoros.errors import ConfigError
from pymotoros.models import RobotModel

F64Array = npt.NDArray[np.float64]

JSON_FORMAT: Final = "pymotoros-trajectory"
JSON_VERSION: Final = 1
_NS_PER_S: Final = 1_000_000_000

FORMATS: Final = ("csv", "json", "yaml")


class TrajectoryFileError(ConfigError):
    """A trajectory file that cannot be read: the message names the file and the place."""


@dataclass(frozen=True, slots=True, eq=False)
class Trajectory:
    """Points on one time line: ``times`` (P,), ``positions``/``velocities`` (P, J).

    Row 0 is the start point (sequence 0). Joints in ``joint_names`` order; for a
    CSV file they are the robot's single group in ROS order.
    """

    joint_names: tuple[str, ...]
    times: F64Array
    positions: F64Array
    velocities: F64Array
    robot: str | None = None
    controller: str | None = None

    def __post_init__(self) -> None:
        p = len(self.times)
        j = len(self.joint_names)
        if p == 0:
            raise TrajectoryFileError("a trajectory needs at least its start point")
        if self.positions.shape != (p, j) or self.velocities.shape != (p, j):
            raise TrajectoryFileError(
                f"{p} points of {j} joints need positions and velocities of shape ({p}, {j}), "
                f"got {self.positions.shape} and {self.velocities.shape}"
            )
        for what, arr in (
            ("time", self.times),
            ("position", self.positions),
            ("velocity", self.velocities),
        ):
            if not np.all(np.isfinite(arr)):
                bad = int(np.argwhere(~np.isfinite(arr))[0][0])
                raise TrajectoryFileError(f"point {bad}: a {what} is not a finite number")

    @property
    def duration(self) -> float:
        """Seconds from the first point to the last."""
        return float(self.times[-1] - self.times[0])

    def group_columns(self, robot: RobotModel) -> list[tuple[int, list[int]]]:
        """(group index, columns of its joints in ROS order) for each group the file names.

        A group must be named completely or not at all; a joint the robot does not
        have is an error that lists the robot's joints.
        """
        index = {name: i for i, name in enumerate(self.joint_names)}
        if len(index) != len(self.joint_names):
            raise TrajectoryFileError(f"joint names repeat: {list(self.joint_names)}")
        known = {n for g in robot.groups for n in g.joint_names}
        unknown = [n for n in self.joint_names if n not in known]
        if unknown:
            raise TrajectoryFileError(
                f"{robot.name} has no joint(s) {unknown}; its joints are "
                + "; ".join(f"{g.name}: {', '.join(g.joint_names)}" for g in robot.groups)
            )
        owners: dict[str, list[str]] = {}
        for group in robot.groups:
            for n in group.joint_names:
                owners.setdefault(n, []).append(group.name)
        shared = [n for n in self.joint_names if len(owners[n]) > 1]
        if shared:
            raise TrajectoryFileError(
                f"{robot.name}: joint {shared[0]} belongs to groups "
                f"{', '.join(owners[shared[0]])}, so a trajectory file cannot say which it "
                "moves; describe the cell's groups with robots whose joints are named apart"
            )
        out: list[tuple[int, list[int]]] = []
        for gi, group in enumerate(robot.groups):
            present = [n in index for n in group.joint_names]
            if any(present) and not all(present):
                missing = [n for n, p in zip(group.joint_names, present, strict=True) if not p]
                raise TrajectoryFileError(
                    f"group {group.name} is named only partly; missing {missing}"
                )
            if all(present):
                out.append((gi, [index[n] for n in group.joint_names]))
        return out


# --------------------------------------------------------------------------- reading


def read_trajectory_file(
    path: Path, robot: RobotModel | None = None, fmt: str | None = None
) -> Trajectory:
    """Read ``path`` in ``fmt`` (default: from the suffix: .csv, .json, .yaml/.yml).

    A CSV file names no joints, so it needs ``robot`` (single group).
    """
    fmt = fmt or format_of(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise TrajectoryFileError(f"{path.name}: cannot read it ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise TrajectoryFileError(
            f"{path.name}: not UTF-8 text (byte {exc.start}: {exc.reason}); a trajectory "
            "file is CSV, JSON or YAML text"
        ) from None
    if fmt == "csv":
        if robot is None:
            raise TrajectoryFileError(f"{path.name}: a CSV trajectory needs --robot")
        return parse_csv(text, robot, path.name)
    if fmt == "json":
        return parse_json(text, path.name)
    return parse_yaml(text, path.name)


def format_of(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix == ".csv":
        return "csv"
    if suffix == ".json":
        return "json"
    if suffix in (".yaml", ".yml"):
        return "yaml"
    raise TrajectoryFileError(
        f"{path.name}: cannot tell the format from the suffix {suffix!r}; "
        "use .csv, .json, .yaml or .yml"
    )


def parse_csv(text: str, robot: RobotModel, name: str = "CSV") -> Trajectory:
    """The CSV of ``pymotoros interpolate`` for ``robot``'s single group.

    The file carries no robot name, so the trajectory's ``robot`` stays ``None``.
    """
    if len(robot.groups) != 1:
        raise TrajectoryFileError(
            f"{name}: the CSV format holds one control group; {robot.name} has "
            f"{len(robot.groups)}; use JSON or YAML"
        )
    group = robot.groups[0]
    n = group.num_axes
    rows = [r for r in csv.reader(io.StringIO(text)) if r and any(c.strip() for c in r)]
    if not rows:
        raise TrajectoryFileError(f"{name} is empty; it needs a header row")
    columns = 1 + 2 * n
    data: list[list[float]] = []
    for number, row in enumerate(rows, start=1):
        if len(row) != columns:
            raise TrajectoryFileError(
                f"{name} row {number}: {len(row)} columns, expected {columns} "
                f"(time, {n} positions, {n} velocities for {robot.name})"
            )
        if number == 1:
            continue
        try:
            data.append([float(c) for c in row])
        except ValueError:
            raise TrajectoryFileError(f"{name} row {number}: not all numbers: {row}") from None
    if not data:
        raise TrajectoryFileError(f"{name} has no points after the header")
    arr = np.array(data, dtype=np.float64)
    # The CSV names no robot: ``robot`` only says how to read its columns. Recording
    # robot.name here would pass a cell's name (or the --robot default) off as the file's
    # maker and make ``check --config`` warn that the file was made for another robot.
    return Trajectory(group.joint_names, arr[:, 0], arr[:, 1 : n + 1], arr[:, n + 1 :])


def _floats(value: Any, count: int, where: str) -> list[float]:
    if not isinstance(value, list) or len(value) != count:
        raise TrajectoryFileError(f"{where}: needs a list of {count} numbers, got {value!r}")
    # true/false and "0.5" would pass float(): a JSON or YAML number is an int or a float
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        raise TrajectoryFileError(f"{where}: not all numbers: {value!r:.200}")
    try:
        return [float(v) for v in value]
    except OverflowError:  # an int beyond a double
        raise TrajectoryFileError(f"{where}: not all numbers: {value!r:.200}") from None


def _names_and_points(doc: dict[str, Any], name: str, *, quote: str) -> tuple[list[str], list[Any]]:
    """The ``joint_names`` (non-empty strings) and ``points`` (a non-empty list) of a
    JSON or YAML trajectory; ``quote`` the keys as the format writes them."""
    names = doc.get("joint_names")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise TrajectoryFileError(
            f"{name}: {quote}joint_names{quote} must be a non-empty list of strings"
        )
    points = doc.get("points")
    if not isinstance(points, list) or not points:
        raise TrajectoryFileError(f"{name}: {quote}points{quote} must be a non-empty list")
    return names, points


def _json_time(point: dict[str, Any], where: str) -> float:
    extra = set(point) - {"time", "positions", "velocities"}
    if extra:
        raise TrajectoryFileError(f"{where}: unknown key(s) {sorted(extra)}")
    return _floats([point.get("time")], 1, f"{where} time")[0]


def _ros_time(point: dict[str, Any], where: str) -> float:
    return _duration(point.get("time_from_start"), where)


def _point_rows(
    points: list[Any],
    joints: int,
    name: str,
    kind: str,
    time_of: Callable[[dict[str, Any], str], float],
) -> tuple[F64Array, F64Array, F64Array]:
    """(times, positions, velocities) of the points of a JSON or YAML trajectory; each
    point is ``kind`` (a JSON object, a YAML mapping), its time read by ``time_of``."""
    times, pos, vel = [], [], []
    for i, p in enumerate(points):
        where = f"{name} point {i}"
        if not isinstance(p, dict):
            raise TrajectoryFileError(f"{where}: must be {kind}")
        times.append(time_of(p, where))
        pos.append(_floats(p.get("positions"), joints, f"{where} positions"))
        vel.append(_floats(p.get("velocities"), joints, f"{where} velocities"))
    return np.array(times), np.array(pos), np.array(vel)


def parse_json(text: str, name: str = "JSON") -> Trajectory:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise TrajectoryFileError(f"{name}: not JSON: {exc}") from None
    if not isinstance(doc, dict) or doc.get("format") != JSON_FORMAT:
        raise TrajectoryFileError(f'{name}: needs "format": "{JSON_FORMAT}"')
    if doc.get("version") != JSON_VERSION:
        raise TrajectoryFileError(
            f"{name}: version {doc.get('version')!r}; this pymotoros reads {JSON_VERSION}"
        )
    names, points = _names_and_points(doc, name, quote='"')
    times, pos, vel = _point_rows(points, len(names), name, "an object", _json_time)
    robot = doc.get("robot")
    controller = doc.get("controller")
    return Trajectory(
        tuple(names),
        times,
        pos,
        vel,
        robot=robot if isinstance(robot, str) else None,
        controller=controller if isinstance(controller, str) else None,
    )


def _duration(value: Any, where: str) -> float:
    """A ROS 1 ``{secs, nsecs}`` or ROS 2 ``{sec, nanosec}`` duration in seconds."""
    if not isinstance(value, dict):
        raise TrajectoryFileError(f"{where}: time_from_start must be a mapping, got {value!r}")
    if "secs" in value:
        s, ns = value.get("secs"), value.get("nsecs", 0)
    else:
        s, ns = value.get("sec"), value.get("nanosec", 0)
    if not isinstance(s, int) or not isinstance(ns, int):
        raise TrajectoryFileError(
            f"{where}: time_from_start needs integer secs/nsecs (ROS 1) or sec/nanosec "
            f"(ROS 2), got {value!r}"
        )
    try:
        return s + ns / _NS_PER_S
    except OverflowError:
        raise TrajectoryFileError(
            f"{where}: time_from_start is out of range: {value!r:.200}"
        ) from None


def parse_yaml(text: str, name: str = "YAML") -> Trajectory:
    """A ``trajectory_msgs/JointTrajectory`` as ``rostopic echo``/``ros2 topic echo`` print it."""
    try:
        docs = [d for d in yaml.safe_load_all(text) if d is not None]
    except yaml.YAMLError as exc:
        raise TrajectoryFileError(f"{name}: not YAML: {exc}") from None
    if len(docs) != 1:
        raise TrajectoryFileError(
            f"{name}: holds {len(docs)} messages; keep exactly one (rostopic echo -n 1 prints one)"
        )
    doc = docs[0]
    if not isinstance(doc, dict) or "joint_names" not in doc or "points" not in doc:
        raise TrajectoryFileError(
            f"{name}: not a trajectory_msgs/JointTrajectory (needs joint_names and points)"
        )
    names, points = _names_and_points(doc, name, quote="")
    times, pos, vel = _point_rows(points, len(names), name, "a mapping", _ros_time)
    return Trajectory(tuple(names), times, pos, vel)


# --------------------------------------------------------------------------- writing


def write_trajectory_file(traj: Trajectory, path: Path, fmt: str | None = None) -> None:
    """Write ``traj`` in ``fmt`` (default: from the suffix)."""
    fmt = fmt or format_of(path)
    text = {"csv": to_csv, "json": to_json, "yaml": to_yaml}[fmt](traj)
    path.write_text(text, encoding="utf-8")


def to_csv(traj: Trajectory) -> str:
    n = len(traj.joint_names)
    head = ["time", *(f"p{i}" for i in range(1, n + 1)), *(f"v{i}" for i in range(1, n + 1))]
    lines = [",".join(head)]
    for t, p, v in zip(traj.times, traj.positions, traj.velocities, strict=True):
        lines.append(",".join(repr(float(x)) for x in (t, *p, *v)))
    return "\n".join(lines) + "\n"


def to_json(traj: Trajectory) -> str:
    doc = {
        "format": JSON_FORMAT,
        "version": JSON_VERSION,
        "robot": traj.robot,
        "controller": traj.controller,
        "joint_names": list(traj.joint_names),
        "points": [
            {"time": float(t), "positions": p.tolist(), "velocities": v.tolist()}
            for t, p, v in zip(traj.times, traj.positions, traj.velocities, strict=True)
        ],
    }
    return json.dumps(doc, indent=1) + "\n"


def to_yaml(traj: Trajectory) -> str:
    """ROS 1 ``rostopic echo`` layout (``secs``/``nsecs``)."""

    def stamp(t: float) -> dict[str, int]:
        ns = round(t * _NS_PER_S)
        return {"secs": ns // _NS_PER_S, "nsecs": ns % _NS_PER_S}

    doc = {
        "header": {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""},
        "joint_names": list(traj.joint_names),
        "points": [
            {
                "positions": p.tolist(),
                "velocities": v.tolist(),
                "accelerations": [],
                "effort": [],
                "time_from_start": stamp(float(t)),
            }
            for t, p, v in zip(traj.times, traj.positions, traj.velocities, strict=True)
        ],
    }
    text: str = yaml.safe_dump(doc, sort_keys=False, default_flow_style=None)
    return text + "---\n"
