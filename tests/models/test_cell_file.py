"""One reader for the cell file and one TOML helper for every hand-written file (issue 19).

The simulator (``load_cell``), the client (``load_cell_models``), the fleet
(``read_cell_ports``) and the settings and scenario files fail the same way on a file
that is missing, not UTF-8 or not TOML; the cell's controller and groups, written back in
the cell file's shape (what the ports file carries), read back into the same models.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from pymotoros.cli.settings import load_settings
from pymotoros.controller.cell import cell_from_dict, default_cell, load_cell
from pymotoros.controller.scenario import load_scenario
from pymotoros.errors import ConfigError
from pymotoros.models.cell import (
    cell_models_from_dict,
    load_cell_models,
    read_cell_file,
)
from pymotoros.runtime.fleet import read_cell_ports

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "cells"

READERS: list[tuple[str, Callable[[Path], object]]] = [
    ("cell file", load_cell),
    ("cell file", load_cell_models),
    ("cell file", read_cell_ports),
    ("cell file", read_cell_file),
    ("scenario file", load_scenario),
    ("settings file", lambda path: load_settings(path, ["status"])),
]


@pytest.mark.parametrize(("what", "read"), READERS)
def test_every_toml_file_fails_the_same_way(
    tmp_path: Path, what: str, read: Callable[[Path], object]
) -> None:
    missing = tmp_path / "missing.toml"
    with pytest.raises(ConfigError) as info:
        read(missing)
    assert str(info.value) == f"{missing}: cannot read the {what} (No such file or directory)"

    bad = tmp_path / "bad.toml"
    bad.write_text("[controller\nmodel=", encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        read(bad)
    assert str(info.value).startswith(f"{bad}: not valid TOML: ")

    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"name = \xff\xfe\n")
    with pytest.raises(ConfigError) as info:
        read(binary)
    assert str(info.value).startswith(f"{binary}: the {what} is not UTF-8 text")


def test_a_cell_file_is_read_once_for_every_reader(tmp_path: Path) -> None:
    path = tmp_path / "cell.toml"
    path.write_text(
        'name = "two"\n[controller]\nmodel = "dx100"\nfsu_speed_limit_pct = 50\n'
        '[[groups]]\nrobot = "hc10"\n[[groups]]\nrobot = "sda10f"\n'
        "[ports]\nmotion = 51000\n",
        encoding="utf-8",
    )
    cell_file = read_cell_file(path)
    assert cell_file.ports.motion == 51000
    assert cell_file.ports.http is None
    models = cell_file.models
    sim = load_cell(path)
    assert [g.name for g in models.robot.groups] == [g.name for g in sim.groups]
    assert models.robots == sim.robots == ("hc10", "sda10f", "sda10f")  # DX100: 3 groups
    assert models.model_groups == sim.model_groups == ("R1", "R1", "R2")
    assert models.fsu_speed_limit_pct == sim.servo.fsu_speed_limit_pct == 50
    assert [p.entry for p in cell_file.parts] == [0, 1, 1, 1, 1]  # before the cap
    assert models.warnings == sim.warnings


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.stem)
def test_a_cell_written_back_reads_back_into_the_same_models(path: Path) -> None:
    """What the ports file carries (``CellConfig.as_table``) is a cell file's table."""
    cell = load_cell(path)
    again = cell_models_from_dict(cell.as_table(), source="ports file")
    assert again.controller == cell.controller
    assert again.robot.groups == cell.groups
    assert again.robots == cell.robots
    assert again.name == cell.name


def test_the_default_cell_is_the_cell_of_a_minimal_file() -> None:
    named = default_cell("fs100", "sda10f")
    from_file = cell_from_dict({"controller": {"model": "fs100"}, "robot": {"model": "sda10f"}})
    assert named.groups == from_file.groups
    assert named.robots == from_file.robots
    assert named.pfl == from_file.pfl
    assert named.name == "sda10f on fs100"
    assert named.source == "<default cell>"
    assert cell_models_from_dict(named.as_table()).robot.groups == named.groups
