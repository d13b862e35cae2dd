"""models/cell.py: the part of a cell file the client reads, with the simulator's errors."""

from __future__ import annotations

import pytest

from pymotoros.controller.cell import cell_from_dict
from pymotoros.errors import ConfigError
from pymotoros.models.cell import cell_models_from_dict

BAD_CELLS = [
    ({"groups": [{"robot": "hc10"}, {"robot": "hc99"}]}, "cell.toml: groups[1].robot: "),
    ({"groups": [{"robot": "hc10", "grp": "R1"}]}, "cell.toml: groups[0].grp: unknown key"),
    ({"robot": {"model": "hc10"}, "groups": [{"robot": "hc10"}]}, "give either [robot]"),
    ({"groups": []}, "cell.toml: groups: needs at least one group"),
    ({"robot": {"modle": "hc10"}}, "cell.toml: robot.modle: unknown key (misspelt?)"),
    ({"controller": {"model": "yrc9"}}, "cell.toml: controller.model: "),
]


@pytest.mark.parametrize(("data", "message"), BAD_CELLS)
def test_client_and_simulator_refuse_a_cell_with_the_same_words(
    data: dict[str, object], message: str
) -> None:
    with pytest.raises(ConfigError) as client_side:
        cell_models_from_dict(data, source="cell.toml")
    with pytest.raises(ConfigError) as sim_side:
        cell_from_dict(data, source="cell.toml")
    assert message in str(client_side.value)
    assert message in str(sim_side.value)


def test_sda10f_cell_groups_and_dx100_cap() -> None:
    models = cell_models_from_dict(
        {"controller": {"model": "dx100"}, "robot": {"model": "sda10f"}}, source="c"
    )
    assert [g.name for g in models.robot.groups] == ["R1", "R2", "B1"]
    assert any("at most 3" in w for w in models.warnings)
    assert models.robot.groups[0].num_axes == 7
