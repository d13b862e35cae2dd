"""MotoROS's start-up checks: every 8003 subcode from a cell file, fatal or warning (§8)."""

from __future__ import annotations

from typing import Any

import pytest

from pymotoros.controller import VirtualController, cell_from_dict, signals
from pymotoros.controller.safety.startup import ALARM_POLL_MS
from pymotoros.errors import ConfigError

from .helpers import tick_until

# (cell [controller] keys, robot, expected subcode, fatal)
CASES: list[tuple[dict[str, Any], str, int, bool]] = [
    ({"parameters": {"RS000": 0}}, "hc10", 1, False),
    ({"parameters": {"S2C541": 1}}, "hc10", 2, False),
    ({"parameters": {"S2C542": 1}}, "hc10", 3, False),
    ({"parameters": {"S2C1100": 0}}, "hc10", 4, True),
    ({"parameters": {"S2C1103": 0}}, "hc10", 5, True),
    ({"model": "dx200", "parameters": {"S2C1117": 0}}, "gp7", 6, True),
    ({"parameters": {"S2C1119": 1}}, "hc10", 7, False),
    ({"software": "YAS2.70.00-00"}, "hc10", 8, True),
    ({"software": "XYZ4.00.00-00"}, "hc10", 8, True),
    ({"model": "yrc1000micro", "software": "YBS2.20.00-00"}, "hc10", 8, True),
    ({"validation_code": 9}, "hc10", 9, True),
    ({"validation_code": 10}, "hc10", 10, True),
    ({"conveyor_tracking": True}, "hc10", 11, True),
    ({"validation_code": 102}, "gp7", 102, True),
]


def booted(ctrl: dict[str, Any], robot: str) -> VirtualController:
    return VirtualController(cell_from_dict({"controller": ctrl, "robot": {"model": robot}}))


@pytest.mark.parametrize(("ctrl", "robot", "subcode", "fatal"), CASES)
def test_every_8003_subcode_with_its_effect(
    ctrl: dict[str, Any], robot: str, subcode: int, fatal: bool
) -> None:
    vc = booted(ctrl, robot)
    assert [(a.code, a.subcode) for a in vc.snapshot().alarms] == [(8003, subcode)]
    assert not vc.motoros_started
    assert not vc.io.get(signals.INIT_DONE)
    vc.run_ticks(10)
    assert not vc.motoros_started  # waits until the alarm is reset
    vc.reset()
    vc.tick()
    assert vc.motoros_started is (not fatal)
    assert bool(vc.io.get(signals.INIT_DONE)) is (not fatal)
    if fatal:
        assert "halted" in vc.motoros_phase
        assert f"8003/{subcode}" in vc.motoros_phase
        vc.run_ticks(2 * ALARM_POLL_MS // vc.period_ms)
        assert not vc.motoros_started  # never


@pytest.mark.parametrize(
    "ctrl",
    [
        {},
        {"software": "YAS2.80.00-00"},
        {"software": "YAS4.10.00-00", "parameters": {"S2C1117": 0, "S2C1119": 2}},
    ],
)
def test_passing_configurations_start_at_once(ctrl: dict[str, Any]) -> None:
    vc = booted(ctrl, "hc10")
    assert vc.motoros_started
    assert vc.io.get(signals.INIT_DONE)
    assert vc.snapshot().alarms == ()


def test_version_and_conveyor_do_not_matter_for_a_non_hc_robot() -> None:
    vc = booted({"software": "YAS1.00.00-00", "conveyor_tracking": True}, "gp7")
    assert vc.motoros_started


def test_an_alarm_at_boot_holds_motoros_back_checked_every_2_5_s() -> None:
    cell = cell_from_dict({"initial": {"alarms": [{"code": 4100, "text": "overrun"}]}})
    vc = VirtualController(cell)
    assert not vc.motoros_started
    vc.run_ticks(100)
    vc.reset()
    reset_ms = vc.time_ms
    tick_until(vc, lambda: vc.motoros_started, "MotoROS starts", max_ticks=1000)
    assert vc.time_ms == ALARM_POLL_MS  # the next 2.5 s check after the reset
    assert vc.time_ms > reset_ms


@pytest.mark.parametrize(
    ("ctrl", "key"),
    [
        ({"parameters": {"RS001": 1}}, "controller.parameters.RS001"),
        ({"parameters": {"RS000": "2"}}, "controller.parameters.RS000"),
        ({"software": 2.8}, "controller.software"),
        ({"validation_code": 11}, "controller.validation_code"),
        ({"conveyor_tracking": "yes"}, "controller.conveyor_tracking"),
    ],
)
def test_bad_startup_keys_are_refused_naming_the_key(ctrl: dict[str, Any], key: str) -> None:
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        cell_from_dict({"controller": ctrl})
