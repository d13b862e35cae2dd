"""Issue 21 item 6 on the in-memory twin: a person walks into the cell (a scenario's
``obstacle`` action) and the HC10 sweeping through that spot stops with a PFL contact."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pymotoros.client import NotReadyError
from pymotoros.controller.scenario import load_scenario
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.testing import twin

SCENARIO = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "person_walks_in.toml"
READY = (0.0, 0.5, 0.0, 0.0, 0.0, 0.0)
"""The elbow 0.34 m out from axis S, at the person's chest height."""
SWEEP = (2.5, 0.5, 0.0, 0.0, 0.0, 0.0)
"""Turning S through the person standing at 1.2 rad (0.6 m out)."""
PERSON_AT_RAD = math.atan2(0.56, 0.22)


async def test_person_walking_in_stops_the_hc10_with_a_pfl_contact() -> None:
    async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
        cell.controller.load_scenario(load_scenario(SCENARIO))
        await client.enable()
        await client.move_joints(READY, speed_scale=0.5)
        assert cell.controller.snapshot().time_ms < 3000  # the person is not there yet
        assert cell.controller.snapshot().workspace.obstacles == ()
        with pytest.raises(NotReadyError) as info:
            await client.move_joints(SWEEP, speed_scale=0.2)
        assert info.value.reason is NotReadySubcode.PFL_ACTIVE
        snap = cell.controller.snapshot()
        assert [o.name for o in snap.workspace.obstacles] == ["person"]
        assert snap.safety.pfl == "stop"
        assert [(c.obstacle, c.link) for c in snap.workspace.contacts] == [("person", "link_2_l")]
        s_axis = (await client.current_positions())[0]
        # stopped on the way, before the person's bearing (the elbow meets the body
        # about a capsule's width before the centre line)
        assert 0.3 < s_axis < PERSON_AT_RAD
        assert [e.action for e in cell.controller.fired_events] == ["obstacle"]
        await cell.clock.sleep(max(0.0, 8.2 - cell.controller.snapshot().time_ms / 1000))
        assert cell.controller.snapshot().workspace.obstacles == ()  # walked out again
        assert [e.action for e in cell.controller.fired_events] == ["obstacle", "remove_obstacle"]
