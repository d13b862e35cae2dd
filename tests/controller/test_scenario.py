"""Scenario files: validation naming the event and key; the driver's triggers in virtual time."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from pymotoros.controller import VirtualController, signals
from pymotoros.controller.scenario import ACTIONS, load_scenario, parse_scenario
from pymotoros.errors import ConfigError

from .helpers import CMD, command, point, send, start_at_current, tick_until

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenarios"


@pytest.mark.parametrize(
    ("event", "where"),
    [
        ({"action": "estop", "pressed": True}, r"events\[0\]: needs exactly one trigger"),
        ({"at": 1, "after_motion": 1, "action": "reset"}, "found: at, after_motion"),
        ({"at": 1, "action": "explode"}, r"events\[0\]\.action: must be one of"),
        ({"at": -1, "action": "reset"}, r"events\[0\] \(reset\)\.at: must be a number"),
        ({"at": 1, "action": "estop"}, r"\(estop\)\.pressed: is required"),
        ({"at": 1, "action": "estop", "pressed": 1}, r"\.pressed: must be true or false"),
        ({"at": 1, "action": "hold", "of": True}, r"\(hold\)\.of: unknown key .*its keys: on"),
        ({"at": 1, "action": "mode", "mode": "auto"}, r"\.mode: must be one of teach, play"),
        ({"at": 1, "action": "fsu"}, "needs joint_speed_pct"),
        ({"at": 1, "action": "fsu", "joint_speed_pct": 0}, r"\.joint_speed_pct: must lie in"),
        ({"at": 1, "action": "pfl", "event": "contact", "retreat_ms": 5}, "clamping only"),
        ({"when_io": {"address": 1}, "action": "reset"}, r"\.when_io: must be"),
        ({"at": 1, "action": "alarm", "code": 10000}, r"\.code: must lie in 0\.\.9999"),
    ],
)
def test_a_bad_event_is_refused_naming_the_event_and_the_key(
    event: dict[str, Any], where: str
) -> None:
    with pytest.raises(ConfigError, match=where):
        parse_scenario({"events": [event]})


def test_a_bad_file_is_refused_before_anything_runs(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[[events]]\nat = 1\naction = "reset"\n\n[[events]]\nat = 2\naction = "hold"\n')
    with pytest.raises(ConfigError, match=r"bad\.toml: events\[1\] \(hold\)\.on: is required"):
        load_scenario(bad)
    with pytest.raises(ConfigError, match="at least one"):
        parse_scenario({"events": []})
    with pytest.raises(ConfigError, match="unknown key"):
        parse_scenario({"events": [{"at": 1, "action": "reset"}], "evnts": []})


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.name)
def test_every_example_scenario_is_valid(path: Path) -> None:
    scenario = load_scenario(path)
    assert scenario.events
    assert all(e.action in ACTIONS for e in scenario.events)


def test_at_and_when_io_fire_once_at_their_tick_and_are_listed() -> None:
    vc = VirtualController()
    vc.load_scenario(
        parse_scenario(
            {
                "events": [
                    {"at": 0.1, "action": "hold", "on": True},
                    {"when_io": {"address": signals.HOLD, "value": 1}, "action": "io",
                     "address": 10010, "value": 1},
                    {"at": 0.2, "action": "pfl", "event": "contact"},
                ]
            }
        )
    )  # fmt: skip
    tick_until(vc, lambda: vc.snapshot().hold, "hold", max_ticks=100)
    assert vc.time_ms == 100
    vc.run_ticks(60)
    fired = vc.fired_events
    assert [(f.t, f.action) for f in fired] == [(0.1, "hold"), (0.104, "io"), (0.2, "pfl")]
    assert vc.io.get(10010) == 1
    assert "stands still" in fired[2].error  # refused, logged, listed with the reason


def test_after_motion_counts_from_the_first_increment_of_the_next_trajectory() -> None:
    vc = VirtualController()
    vc.load_scenario(
        parse_scenario(
            {
                "events": [
                    {"after_motion": 0.5, "action": "pfl", "event": "contact"},
                    {"after_motion": 0.6, "action": "fsu", "joint_speed_pct": 40},
                ]
            }
        )
    )
    vc.run_ticks(500)  # two idle seconds: nothing fires
    assert vc.fired_events == ()
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert start_at_current(vc).ok
    assert send(vc, 1, point(0, 2.0, [0.5, 0, 0, 0, 0, 0])).ok
    tick_until(vc, vc.has_queued_motion, "moving", max_ticks=5)
    tick_until(vc, lambda: bool(vc.fired_events), "contact", max_ticks=200)
    first_move_ms = vc.time_ms - 500
    assert vc.fired_events[0].action == "pfl"
    assert vc.fired_events[0].error == ""
    assert vc.io.get(signals.PFL_STOP) == 1
    vc.run_ticks(30)
    assert [f.action for f in vc.fired_events] == ["pfl", "fsu"]
    assert vc.fired_events[1].t - vc.fired_events[0].t == pytest.approx(0.1)
    assert vc.safety.fsu.active.joint_speed_pct == 40
    assert first_move_ms > 0
