"""Every example scenario end to end with the client, in virtual time (the twin)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pymotoros.client import NotReadyError, RobotClient
from pymotoros.client.errors import ClientError
from pymotoros.controller import cell_from_dict
from pymotoros.controller.scenario import load_scenario, parse_scenario
from pymotoros.protocol.constants import NotReadySubcode
from pymotoros.testing import Twin, twin

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
GOAL = (1.0, 0.3, 0.2, 0.0, -1.0, 0.5)
LONG_GOAL = (2.5, 0.3, 0.2, 0.0, -1.0, 0.5)
TOLERANCE = 1e-3
RETRY_S = 0.05
RETRIES = 200
"""Enable retries while the fault is still on: 10 s of virtual time at most."""


async def enable_when_possible(client: RobotClient, cell: Twin) -> int:
    """Enable, retrying (virtual time) while the fault still refuses it; the retries used."""
    for attempt in range(RETRIES):
        try:
            await client.enable()
        except NotReadyError:
            await cell.clock.sleep(RETRY_S)
        else:
            return attempt
    pytest.fail("could not enable again")


async def move_recovering(client: RobotClient, cell: Twin, goal: tuple[float, ...]) -> int:
    """move_joints to ``goal``; on a refusal, enable again and retry. The refusals seen."""
    refusals = 0
    for _ in range(3):
        try:
            await client.move_joints(goal, speed_scale=0.3)
        except ClientError:
            refusals += 1
            await enable_when_possible(client, cell)
        else:
            return refusals
    pytest.fail("the move never completed")


def _off(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    return max(abs(x - y) for x, y in zip(a, b, strict=True))


async def test_pfl_contact_scenario_gives_the_typed_5011_and_recovers() -> None:
    async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
        cell.controller.load_scenario(load_scenario(SCENARIOS / "pfl_contact.toml"))
        await client.enable()
        with pytest.raises(NotReadyError) as info:
            await client.move_joints(GOAL, speed_scale=0.3)
        assert info.value.reason is NotReadySubcode.PFL_ACTIVE
        assert "PFL" in info.value.remedy
        retries = await enable_when_possible(client, cell)
        assert retries > 0  # refused while PFL stop was on
        result = await client.move_joints(GOAL, speed_scale=0.3)
        assert _off(GOAL, result.final_positions) < TOLERANCE
        assert [e.action for e in cell.controller.fired_events] == ["pfl"]


async def test_estop_recovery_scenario() -> None:
    async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
        cell.controller.load_scenario(load_scenario(SCENARIOS / "estop_recovery.toml"))
        await client.enable()
        assert await move_recovering(client, cell, GOAL) == 1
        assert _off(GOAL, await client.current_positions()) < TOLERANCE
        fired = cell.controller.fired_events
        assert [(e.action, dict(e.params)) for e in fired] == [
            ("estop", {"pressed": True}),
            ("estop", {"pressed": False}),
            ("reset", {}),
        ]
        assert fired[1].t - fired[0].t == pytest.approx(1.0)


async def test_fsu_long_move_scenario_is_slower_and_ends_at_the_target() -> None:
    async def duration(scenario: bool) -> tuple[float, tuple[float, ...]]:
        async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
            if scenario:
                cell.controller.load_scenario(load_scenario(SCENARIOS / "fsu_long_move.toml"))
            await client.enable()
            start = cell.clock.now()
            result = await client.move_joints(LONG_GOAL, speed_scale=0.5)
            if scenario:
                assert [e.action for e in cell.controller.fired_events] == ["fsu", "fsu"]
            return cell.clock.now() - start, result.final_positions

    free_s, free_end = await duration(False)
    slow_s, slow_end = await duration(True)
    assert _off(free_end, slow_end) < TOLERANCE
    assert _off(LONG_GOAL, slow_end) < TOLERANCE
    assert slow_s > free_s + 0.5


async def test_eco_brake_sag_scenario() -> None:
    cell_cfg = cell_from_dict({"controller": {"brake_sag_pulses": 200}})
    async with twin(cell=cell_cfg, timeout_s=2.0) as (client, cell):
        cell.controller.load_scenario(load_scenario(SCENARIOS / "eco_brake_sag.toml"))
        await client.enable()
        before = cell.controller.snapshot().groups[0].command_rad
        await client.wait_until(
            lambda s: s.status is not None and not s.status.drives_powered, 10.0, "eco mode"
        )
        assert cell.controller.operator_state.eco
        after = cell.controller.snapshot().groups[0].command_rad
        assert after != before  # the brakes let the axes sag
        result = await client.move_joints(GOAL, speed_scale=0.5)  # enable wakes eco mode
        assert _off(GOAL, result.final_positions) < TOLERANCE


async def test_drop_motion_closes_the_motion_connection() -> None:
    async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
        cell.controller.load_scenario(
            parse_scenario({"events": [{"at": 0.5, "action": "drop_motion"}]})
        )
        await cell.clock.sleep(1.0)
        assert cell.controller.fired_events[0].error == ""
        with pytest.raises(ClientError):
            await client.enable()


async def test_the_following_monitor_reports_an_fsu_slowdown_in_rad_and_percent(
    caplog: pytest.LogCaptureFixture,
) -> None:
    reports = {}
    for pct in (None, 30):
        async with twin(robot="hc10", timeout_s=2.0) as (client, cell):
            await client.enable()
            if pct is not None:
                cell.controller.set_fsu(joint_speed_pct=pct)
            result = await client.move_joints(LONG_GOAL)
            assert _off(LONG_GOAL, result.final_positions) < TOLERANCE
            reports[pct] = result.following
    free, slowed = reports[None], reports[30]
    assert not free.slowed
    assert free.min_speed_pct > 90
    assert slowed.slowed
    assert slowed.min_speed_pct < 40  # the FSU let 30 % of the axis maximum through
    assert slowed.max_lag_rad > 10 * free.max_lag_rad
    assert "rad) behind the plan" in caplog.text
    assert "% of the planned speed" in caplog.text
