"""The cell's workspace as data: obstacles (box, cylinder, sphere) and where each group stands.

A cell file may describe what stands around the robot, so that the twin can stop a
robot that touches it, ``pymotoros check`` can warn before a crash and ``plan --avoid``
can go around it (docs/workspace.md)::

    [[workspace.obstacles]]
    name = "table"
    box = [1.2, 0.8, 0.05]        # full sizes x, y, z (m)
    xyz = [0.6, 0.0, -0.03]       # centre (m) in the first group's base_link frame
    rpy_deg = [0, 0, 0]           # optional orientation (fixed axes X, Y, Z)

Multi-robot cells: ``frame = "R2"`` gives an obstacle in group R2's ``base_link``
frame, and ``[workspace.bases.R2]`` (``xyz``, ``rpy_deg``) says where that frame sits
in the workspace frame (the first group's ``base_link``). Groups of one robot model
(the SDA10F's arms and torso) share its ``base_link``; a group without an entry stands
at the workspace origin.

Pure data and checks, numpy-free, so the simulator, the client and ``check``/``plan``
read the same table the same way; every mistake is a
:class:`~pymotoros.errors.ConfigError` naming its key
(``workspace.obstacles[2].box: ...``). The geometry itself is computed in
:mod:`pymotoros.kinematics.collision`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Final, Protocol

from pymotoros.errors import ConfigError
from pymotoros.models.robots import Transform, Vec3

SHAPE_KEYS: Final = ("box", "cylinder", "sphere")
"""The shape keys of an obstacle; exactly one of them is given."""
OBSTACLE_KEYS: Final = frozenset({"name", "xyz", "rpy_deg", "frame", *SHAPE_KEYS})
WORKSPACE_KEYS: Final = frozenset({"obstacles", "bases", "tool_radius_m"})
BASE_KEYS: Final = frozenset({"xyz", "rpy_deg"})
MAX_SIZE_M: Final = 100.0
"""Largest size of an obstacle: a cell is a room, not a landscape (catches mm typed as m)."""
MAX_OBSTACLES: Final = 1000
DEFAULT_TOOL_RADIUS_M: Final = 0.03
"""Radius of the capsule from tool0 to the TCP of the active tool: a 60 mm gripper or
spindle body (modelling choice; ``workspace.tool_radius_m`` changes it)."""


@dataclass(frozen=True, slots=True)
class Box:
    """A box of full sizes x, y, z (m) centred on its pose."""

    size: Vec3

    def as_dict(self) -> dict[str, object]:
        return {"box": list(self.size)}

    @property
    def bounding_radius(self) -> float:
        return 0.5 * math.sqrt(sum(s * s for s in self.size))


@dataclass(frozen=True, slots=True)
class Cylinder:
    """A cylinder of ``radius`` and full ``length`` (m), its axis along its own z, centred."""

    radius: float
    length: float

    def as_dict(self) -> dict[str, object]:
        return {"cylinder": [self.radius, self.length]}

    @property
    def bounding_radius(self) -> float:
        return math.hypot(self.radius, 0.5 * self.length)


@dataclass(frozen=True, slots=True)
class Sphere:
    """A sphere of ``radius`` (m)."""

    radius: float

    def as_dict(self) -> dict[str, object]:
        return {"sphere": self.radius}

    @property
    def bounding_radius(self) -> float:
        return self.radius


Shape = Box | Cylinder | Sphere


@dataclass(frozen=True, slots=True)
class Capsule:
    """A capsule: the points within ``radius`` of a segment ``length`` long along its
    own z, centred (a tool's shape only: a spindle, a gripper's fingers)."""

    radius: float
    length: float

    def as_dict(self) -> dict[str, object]:
        return {"capsule": [self.radius, self.length]}

    @property
    def bounding_radius(self) -> float:
        return 0.5 * self.length + self.radius


TOOL_SHAPE_KEYS: Final = ("capsule", "box", "cylinder", "sphere")
"""The shape keys of a tool's ``shape`` table; exactly one of them is given."""
TOOL_SHAPE_TABLE_KEYS: Final = frozenset({"xyz", "rpy_deg", *TOOL_SHAPE_KEYS})


@dataclass(frozen=True, slots=True)
class ToolShape:
    """The collision shape of a tool (``shape`` in its ``[[tools]]`` entry), on the flange.

    ``pose`` is the shape's centre and orientation in ``tool0``'s frame (the flange).
    Without ``xyz`` the shape stands on the flange, along tool0's z: its centre half its
    length out (a capsule's segment runs from the flange to ``length``)."""

    shape: Capsule | Box | Cylinder | Sphere
    pose: Transform = field(default_factory=Transform)

    def as_dict(self) -> dict[str, object]:
        out = self.shape.as_dict()
        out["xyz"] = list(self.pose.xyz)
        out["rpy_deg"] = [math.degrees(a) for a in self.pose.rpy]
        return out


@dataclass(frozen=True, slots=True)
class Obstacle:
    """One obstacle: its name, shape and pose (in the frame it was given in)."""

    name: str
    shape: Shape
    pose: Transform = field(default_factory=Transform)
    """Centre and orientation (rad, R = Rz·Ry·Rx) in ``frame``."""
    frame: str = ""
    """The group whose ``base_link`` the pose is given in ("" : the workspace frame)."""

    def as_dict(self) -> dict[str, object]:
        """The obstacle in the cell file's keys (for JSON: the state document, the API)."""
        out: dict[str, object] = {"name": self.name, **self.shape.as_dict()}
        out["xyz"] = list(self.pose.xyz)
        out["rpy_deg"] = [math.degrees(a) for a in self.pose.rpy]
        if self.frame:
            out["frame"] = self.frame
        return out


@dataclass(frozen=True, slots=True)
class Workspace:
    """The ``[workspace]`` table of a cell: obstacles, group placements, tool radius."""

    obstacles: tuple[Obstacle, ...] = ()
    bases: Mapping[str, Transform] = field(default_factory=dict)
    """Per group name, where its ``base_link`` sits in the workspace frame."""
    tool_radius_m: float = DEFAULT_TOOL_RADIUS_M

    def base(self, group: str) -> Transform:
        """Where ``group``'s ``base_link`` sits (the origin when the cell does not say)."""
        return self.bases.get(group, Transform())

    def obstacle(self, name: str) -> Obstacle | None:
        return next((o for o in self.obstacles if o.name == name), None)

    def with_obstacle(self, obstacle: Obstacle) -> Workspace:
        """A copy with ``obstacle`` added, or replacing the one of the same name."""
        kept = tuple(o for o in self.obstacles if o.name != obstacle.name)
        if len(kept) >= MAX_OBSTACLES:
            raise ConfigError(f"a workspace holds at most {MAX_OBSTACLES} obstacles")
        return Workspace((*kept, obstacle), self.bases, self.tool_radius_m)

    def without(self, name: str) -> Workspace:
        """A copy without the obstacle ``name`` (:class:`UnknownObstacleError`, a
        ConfigError, when there is none)."""
        if self.obstacle(name) is None:
            raise UnknownObstacleError(name, self.names)
        kept = tuple(o for o in self.obstacles if o.name != name)
        return Workspace(kept, self.bases, self.tool_radius_m)

    @property
    def names(self) -> str:
        return ", ".join(o.name for o in self.obstacles)


EMPTY_WORKSPACE: Final = Workspace()


class UnknownObstacleError(ConfigError, LookupError):
    """An obstacle named that is not in the workspace (the message lists the known ones):
    the control API answers it with 404, not with the 400 of a bad value."""

    def __init__(self, name: str, known: str) -> None:
        super().__init__(f"no obstacle named {name!r}; obstacles: {known or 'none'}")
        self.name = name


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _numbers(value: object, count: int) -> list[float] | None:
    if not isinstance(value, list | tuple) or len(value) != count:
        return None
    out = [_number(v) for v in value]
    return None if any(v is None for v in out) else [v for v in out if v is not None]


def _sizes(value: object, key: str, count: int, what: str) -> list[float]:
    sizes = [_number(value)] if count == 1 else _numbers(value, count)
    if sizes is None or any(s is None or not 0 < s <= MAX_SIZE_M for s in sizes):
        raise ConfigError(f"{key}: must be {what}, each > 0 and ≤ {MAX_SIZE_M:g} m, not {value!r}")
    return [s for s in sizes if s is not None]


def _shape(entry: Mapping[str, object], key: str) -> Shape:
    given = [k for k in SHAPE_KEYS if k in entry]
    if len(given) != 1:
        problem = "gives none" if not given else f"gives {' and '.join(given)}"
        raise ConfigError(
            f"{key}: an obstacle has exactly one of box, cylinder, sphere; it {problem}"
        )
    kind = given[0]
    value = entry[kind]
    if kind == "box":
        x, y, z = _sizes(value, f"{key}.box", 3, "three full sizes [x, y, z] in metres")
        return Box((x, y, z))
    if kind == "cylinder":
        r, length = _sizes(value, f"{key}.cylinder", 2, "[radius, length] in metres")
        return Cylinder(r, length)
    (r,) = _sizes(value, f"{key}.sphere", 1, "a radius in metres")
    return Sphere(r)


def parse_tool_shape(value: object, key: str) -> ToolShape:
    """A tool's ``shape`` table (``key`` is its path, ``tools[0].shape``, for errors):
    exactly one of ``capsule = [radius, length]``, ``box = [x, y, z]``, ``cylinder =
    [radius, length]``, ``sphere = radius`` (m), and optionally ``xyz`` (m) and
    ``rpy_deg`` on tool0 (default: standing on the flange, see :class:`ToolShape`)."""
    if not isinstance(value, Mapping):
        raise ConfigError(
            f"{key}: must be a table such as {{capsule = [0.03, 0.2]}} (radius, length in "
            f"metres, along the flange's z), not {value!r}"
        )
    _unknown(value, TOOL_SHAPE_TABLE_KEYS, key)
    given = [k for k in TOOL_SHAPE_KEYS if k in value]
    if len(given) != 1:
        problem = "gives none" if not given else f"gives {' and '.join(given)}"
        raise ConfigError(
            f"{key}: a tool shape has exactly one of capsule, box, cylinder, sphere; it {problem}"
        )
    shape: Capsule | Shape
    if given[0] == "capsule":
        r, length = _sizes(value["capsule"], f"{key}.capsule", 2, "[radius, length] in metres")
        shape = Capsule(r, length)
        half = length / 2
    else:
        shape = _shape(value, key)
        half = _half_length(shape)
    pose = _pose(value, key, need_xyz=False)
    if "xyz" not in value:
        pose = Transform((0.0, 0.0, half), pose.rpy)
    return ToolShape(shape, pose)


def _half_length(shape: Shape) -> float:
    """Half a shape's length along its own z (how far its centre stands off the flange)."""
    if isinstance(shape, Box):
        return shape.size[2] / 2
    if isinstance(shape, Cylinder):
        return shape.length / 2
    return shape.radius


def _pose(entry: Mapping[str, object], key: str, *, need_xyz: bool) -> Transform:
    xyz_value = entry.get("xyz")
    if xyz_value is None and need_xyz:
        raise ConfigError(f"{key}.xyz: is required: the centre [x, y, z] in metres")
    xyz = _numbers(xyz_value, 3) if xyz_value is not None else [0.0, 0.0, 0.0]
    if xyz is None or any(abs(v) > MAX_SIZE_M for v in xyz):
        raise ConfigError(
            f"{key}.xyz: must be three numbers [x, y, z] in metres, not {xyz_value!r}"
        )
    rpy_value = entry.get("rpy_deg")
    rpy = _numbers(rpy_value, 3) if rpy_value is not None else [0.0, 0.0, 0.0]
    if rpy is None:
        raise ConfigError(
            f"{key}.rpy_deg: must be three angles [roll, pitch, yaw] in degrees, not {rpy_value!r}"
        )
    return Transform(
        (xyz[0], xyz[1], xyz[2]),
        (math.radians(rpy[0]), math.radians(rpy[1]), math.radians(rpy[2])),
    )


def _unknown(entry: Mapping[str, object], allowed: frozenset[str], key: str) -> None:
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise ConfigError(
            f"{key}.{unknown[0]}: unknown key (misspelt?); known: {', '.join(sorted(allowed))}"
        )


def parse_obstacle(entry: object, key: str, groups: Sequence[str] = ()) -> Obstacle:
    """One obstacle from its TOML (or JSON) keys; ``key`` prefixes every error.

    ``groups`` are the cell's group names a ``frame`` may name (empty: any frame refused
    but the empty one).
    """
    if not isinstance(entry, Mapping):
        raise ConfigError(f"{key}: must be a table with name, a shape and xyz, not {entry!r}")
    _unknown(entry, OBSTACLE_KEYS, key)
    name = entry.get("name")
    if not isinstance(name, str) or not name.strip() or "/" in name:
        raise ConfigError(f"{key}.name: must be a non-empty name without '/', not {name!r}")
    frame = entry.get("frame", "")
    if not isinstance(frame, str) or (frame and frame not in groups):
        known = ", ".join(groups) or "none"
        raise ConfigError(f"{key}.frame: must name a group of the cell ({known}), not {frame!r}")
    return Obstacle(name, _shape(entry, key), _pose(entry, key, need_xyz=True), frame)


def workspace_from_dict(value: object, source: str, groups: Sequence[str]) -> Workspace:
    """The ``[workspace]`` table of a parsed cell file (None: an empty workspace)."""
    if value is None:
        return EMPTY_WORKSPACE
    try:
        return _workspace(value, groups)
    except ConfigError as exc:
        raise ConfigError(f"{source}: {exc}") from None


def _workspace(value: object, groups: Sequence[str]) -> Workspace:
    if not isinstance(value, Mapping):
        raise ConfigError(f"workspace: must be a table, not {value!r}")
    _unknown(value, WORKSPACE_KEYS, "workspace")
    entries = value.get("obstacles", [])
    if not isinstance(entries, list):
        raise ConfigError(
            "workspace.obstacles: must be an array of tables ([[workspace.obstacles]])"
        )
    if len(entries) > MAX_OBSTACLES:
        raise ConfigError(f"workspace.obstacles: at most {MAX_OBSTACLES} obstacles")
    obstacles: list[Obstacle] = []
    for i, entry in enumerate(entries):
        obstacle = parse_obstacle(entry, f"workspace.obstacles[{i}]", groups)
        if any(o.name == obstacle.name for o in obstacles):
            raise ConfigError(
                f"workspace.obstacles[{i}].name: {obstacle.name!r} is used twice; names are unique"
            )
        obstacles.append(obstacle)
    bases_value = value.get("bases", {})
    if not isinstance(bases_value, Mapping):
        raise ConfigError("workspace.bases: must be a table of groups ([workspace.bases.R2])")
    bases: dict[str, Transform] = {}
    for group, entry in bases_value.items():
        key = f"workspace.bases.{group}"
        if group not in groups:
            raise ConfigError(f"{key}: no such group (groups: {', '.join(groups)})")
        if not isinstance(entry, Mapping):
            raise ConfigError(f"{key}: must be a table with xyz and rpy_deg")
        _unknown(entry, BASE_KEYS, key)
        bases[group] = _pose(entry, key, need_xyz=False)
    radius_value = value.get("tool_radius_m", DEFAULT_TOOL_RADIUS_M)
    radius = _number(radius_value)
    if radius is None or not 0 < radius <= 1:
        raise ConfigError(f"workspace.tool_radius_m: must be in (0, 1] m, not {radius_value!r}")
    return Workspace(tuple(obstacles), bases, radius)


class ContactLike(Protocol):
    """A contact as a collision model reports it (obstacle or, for a self-collision, the
    other link; the link touching; its group; the distance). Declared here, beside the
    obstacles, so the planner (kinematics) and the offline check (trajectory) share it."""

    @property
    def obstacle(self) -> str: ...
    @property
    def link(self) -> str: ...
    @property
    def group(self) -> str: ...
    @property
    def distance_m(self) -> float: ...
    @property
    def self_collision(self) -> bool: ...



@dataclass(slots=True)
class ContactSpan:
    """One contact over time: ``link`` of ``group`` touches ``obstacle`` (for a
    self-collision: the other link) from ``start_s`` to ``end_s``, at most ``depth_mm``
    deep; ``at_start``: it was there at the first probe (where the motion starts)."""

    group: str
    link: str
    obstacle: str
    self_collision: bool
    start_s: float
    depth_mm: float
    at_start: bool
    end_s: float = 0.0


class ContactSpans:
    """Contacts reported by successive probes of a motion, as spans: a contact opens at
    the first probe that reports it, deepens while reported and closes at the first
    probe that does not. The planner's sweep (kinematics) and the offline check
    (trajectory) both read their probes this way, so one place says when a contact
    starts, how deep it gets and when it ends."""

    __slots__ = ("closed", "open")

    def __init__(self) -> None:
        self.open: dict[tuple[str, str, str], ContactSpan] = {}
        """The contacts the latest probe reported, by (group, link, obstacle)."""
        self.closed: list[ContactSpan] = []
        """The contacts that have ended, in the order they ended."""

    def update(self, hits: Iterable[ContactLike], now_s: float, *, at_start: bool = False) -> None:
        """The probe at ``now_s`` reported ``hits``: open the new contacts, deepen the
        running ones, close those it did not report."""
        seen = set()
        for c in hits:
            key = (c.group, c.link, c.obstacle)
            seen.add(key)
            depth = -c.distance_m * 1000.0
            span = self.open.get(key)
            if span is None:
                self.open[key] = ContactSpan(
                    c.group, c.link, c.obstacle, bool(c.self_collision), now_s, depth, at_start
                )
            elif depth > span.depth_mm:
                span.depth_mm = depth
        for key in [k for k in self.open if k not in seen]:
            span = self.open.pop(key)
            span.end_s = now_s
            self.closed.append(span)

    def close_all(self, end_s: float) -> list[ContactSpan]:
        """Every span: the ended ones, then those still open, ending at ``end_s``."""
        for span in self.open.values():
            span.end_s = end_s
            self.closed.append(span)
        self.open.clear()
        return self.closed


__all__ = [
    "DEFAULT_TOOL_RADIUS_M",
    "EMPTY_WORKSPACE",
    "TOOL_SHAPE_KEYS",
    "Box",
    "Capsule",
    "ContactLike",
    "ContactSpan",
    "ContactSpans",
    "Cylinder",
    "Obstacle",
    "Shape",
    "Sphere",
    "ToolShape",
    "UnknownObstacleError",
    "Workspace",
    "parse_obstacle",
    "parse_tool_shape",
    "workspace_from_dict",
]
