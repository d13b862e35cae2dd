"""The vectorised pulse → joint conversion equals the motion engine's, bit for bit."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.controller import default_cell
from pymotoros.controller.units import RosConverter
from pymotoros.motion import GroupAxes, from_pulses

PULSES = st.lists(st.integers(min_value=-(2**31), max_value=2**31 - 1), min_size=8, max_size=8)


@pytest.mark.parametrize(
    ("controller", "robot"),
    [("yrc1000", "hc10"), ("fs100", "sda10f"), ("dx200", "sia20d"), ("dx100", "mh5")],
)
@settings(max_examples=50, deadline=None)
@given(pulses=PULSES)
def test_same_as_from_pulses(controller: str, robot: str, pulses: list[int]) -> None:
    cell = default_cell(controller, robot)
    for group in cell.groups:
        axes = GroupAxes.from_model(group, cell.controller)
        assert RosConverter(axes)(pulses) == from_pulses(pulses, axes)
