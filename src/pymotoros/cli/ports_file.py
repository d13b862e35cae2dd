"""The ports file: where a ``pymotoros sim`` on port 0 listens, and what each cell is.

``pymotoros sim --ports-file FILE`` writes, once every cell listens (docs/sim.md)::

    {"motion": 41871, "state": 40111, "io": 35667, "http": 44317,
     "cells": [{"cell": "fs100", "name": "sda10f on fs100", "config": "fs100.toml",
                "motion": 41871, "state": 40111, "io": 35667, "http": 44317,
                "controller": "fs100", "robots": ["sda10f"],
                "groups": [{"name": "R1", "robot": "sda10f", "group": "R1"}, ...]}]}

The top-level ports are the first cell's (what readers before several cells read). Each
entry of ``cells`` also says what the cell is (its controller, and each group's robot
model and name in that model), so that a robot command reading the file talks to the
twin in its byte order with its groups and needs no ``--controller``/``--robot``; with
several cells, ``--cell NAME`` chooses one.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from pymotoros.errors import ConfigError
from pymotoros.models.cell import PORT_KINDS, CellModels, cell_models_from_dict

if TYPE_CHECKING:
    from pymotoros.controller.cell import CellConfig

__all__ = [
    "CellLabel",
    "PortsFileCell",
    "ports_file_target",
    "read_ports",
    "read_ports_file_cell",
    "write_ports_file",
]

MOTOROS_PORTS: Final = ("motion", "state", "io")
"""The ports every ports file names (``http`` may be null: no control API)."""


@dataclass(frozen=True, slots=True)
class CellLabel:
    """What the ports file says about a cell besides its ports."""

    name: str
    """The cell's short name: ``--cell NAME``, and ``cell=NAME`` on a fleet's ready lines."""
    table: Mapping[str, Any] | None = None
    """Its name, controller and groups in the cell file's shape
    (:meth:`pymotoros.controller.cell.CellConfig.as_table`); None: not told."""
    config: Path | None = None
    """The cell file it was read from (None: ``--controller``/``--robot``)."""

    @classmethod
    def of(cls, name: str, cell: CellConfig, config: Path | None = None) -> CellLabel:
        """The label of a simulated cell; each group also carries the controller's name
        for it (R1, R2, B1 …), which a cell file does not write."""
        table = cell.as_table()
        pairs = zip(cell.groups, table["groups"], strict=True)
        groups = [{"name": g.name, **entry} for g, entry in pairs]
        return cls(name, {**table, "groups": groups}, config)

    def entry(self, ports: Sequence[int | None]) -> dict[str, Any]:
        """Its ``cells`` entry, with its bound ports in
        :data:`~pymotoros.models.cell.PORT_KINDS` order."""
        entry: dict[str, Any] = {
            "cell": self.name,
            "name": self.name if self.table is None else self.table["name"],
            "config": None if self.config is None else str(self.config),
            **dict(zip(PORT_KINDS, ports, strict=True)),
        }
        if self.table is not None:
            groups = self.table["groups"]
            entry["controller"] = self.table["controller"]["model"]
            entry["robots"] = list(dict.fromkeys(g["robot"] for g in groups))
            entry["groups"] = groups
        return entry


def write_ports_file(
    path: Path,
    motion: int,
    state: int,
    io: int,
    http: int | None,
    *,
    cells: list[dict[str, Any]] | None = None,
) -> None:
    """Write the ports as JSON, atomically (a reader never sees half a file): robot
    commands read it with ``--ports-file`` / ``PYMOTOROS_PORTS_FILE``. The top-level
    ports are the first cell's and ``cells`` lists every cell (:func:`cell_entry`)."""
    data: dict[str, Any] = {"motion": motion, "state": state, "io": io, "http": http}
    if cells is not None:
        data["cells"] = cells
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data) + "\n", encoding="utf-8")
    tmp.replace(path)


@dataclass(frozen=True, slots=True)
class PortsFileCell:
    """The cell a robot command talks to, as the ports file describes it."""

    ports: dict[str, int]
    """motion, state, io (and http when the cell has a control API)."""
    name: str | None = None
    """The cell's short name (None: a ports file that lists no cells)."""
    models: CellModels | None = None
    """Its controller and groups (None: a ports file written before it carried them)."""

    def named_by(self, path: Path | None) -> str | None:
        """Who names the models, for a warning that --controller/--robot are ignored."""
        if self.models is None:
            return None
        return f"the ports file {path} (cell {self.name})"


def _ports(data: Mapping[str, Any], path: Path, where: str) -> dict[str, int]:
    if not all(isinstance(data.get(k), int) for k in MOTOROS_PORTS):
        raise ConfigError(f"{path}: not a ports file ({where}needs motion, state and io numbers)")
    return {k: v for k in PORT_KINDS if isinstance(v := data.get(k), int)}


def _load(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(
            f"{path}: cannot read the ports file ({exc.strerror}); start "
            f"`pymotoros sim --ports-file {path}` first"
        ) from exc
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: not a ports file (not JSON: {exc})") from exc
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: not a ports file (needs motion, state and io numbers)")
    return data


def _choose(path: Path, cells: Sequence[Mapping[str, Any]], cell: str | None) -> Mapping[str, Any]:
    names = [str(c.get("cell")) for c in cells]
    listed = ", ".join(names)
    if cell is None:
        if len(cells) > 1:
            raise ConfigError(
                f"{path}: the simulator runs {len(cells)} cells ({listed}): choose one "
                f"with --cell NAME (or PYMOTOROS_CELL)"
            )
        return cells[0]
    if cell not in names:
        raise ConfigError(f"{path}: no cell {cell!r} in this simulator (its cells: {listed})")
    return cells[names.index(cell)]


def _models(entry: Mapping[str, Any], path: Path, name: str) -> CellModels | None:
    """The cell's controller and groups, read back by the cell file's own reader."""
    if "controller" not in entry or "groups" not in entry:
        return None  # written before the ports file carried the cell
    groups = entry["groups"]
    if isinstance(groups, list):  # a group's "name" is the controller's, not a file key
        groups = [
            {k: v for k, v in g.items() if k != "name"} if isinstance(g, Mapping) else g
            for g in groups
        ]
    robots = entry.get("robots")
    title = entry.get("name", name)
    if entry.get("config") is None and isinstance(robots, list):
        title = "+".join(map(str, robots))  # no file: the robots, as --robot would say
    table = {"name": title, "controller": {"model": entry["controller"]}}
    return cell_models_from_dict({**table, "groups": groups}, source=f"{path} (cell {name})")


def read_ports_file_cell(path: Path, cell: str | None = None) -> PortsFileCell:
    """The ports of the cell named ``cell`` (``--cell``), or of the only cell, and what
    it is; a ConfigError that says what to do when the file is missing, is not a ports
    file, or names several cells and ``cell`` is None."""
    data = _load(path)
    top = _ports(data, path, "")
    cells = data.get("cells")
    if not isinstance(cells, list) or not cells:
        if cell is not None:
            raise ConfigError(
                f"{path}: lists no cells (written by an older pymotoros sim): leave out "
                f"--cell {cell}, or restart the simulator"
            )
        return PortsFileCell(top)
    if not all(isinstance(c, Mapping) for c in cells):
        raise ConfigError(f"{path}: not a ports file (cells must be objects)")
    entry = _choose(path, cells, cell)
    name = str(entry.get("cell"))
    return PortsFileCell(_ports(entry, path, f"cell {name} "), name, _models(entry, path, name))


def read_ports(path: Path) -> dict[str, int]:
    """The top-level ports of a ports file (the first cell's, whatever else it lists)."""
    return _ports(_load(path), path, "")


def ports_file_target(path: Path | None, cell: str | None) -> PortsFileCell:
    """What ``--ports-file`` and ``--cell`` of a robot command say (nothing without a
    ports file; ``--cell`` alone is an error that says what it needs)."""
    if path is not None:
        return read_ports_file_cell(path, cell)
    if cell is not None:
        raise ConfigError(
            f"--cell {cell} chooses a cell of a ports file: give --ports-file FILE (the "
            "file `pymotoros sim --ports-file FILE` wrote) or PYMOTOROS_PORTS_FILE"
        )
    return PortsFileCell({})
