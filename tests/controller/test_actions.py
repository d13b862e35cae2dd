"""The control surface's declarations (controller/actions.py) and the scenario format
derived from them: names, bounds, rules, and the words of a refusal."""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Final

import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.actions import (
    CONTROL_ACTIONS,
    ActionParamError,
    ActionSpec,
    Param,
    actions_by_name,
)
from pymotoros.controller.safety import SAFETY_ACTIONS
from pymotoros.controller.scenario import ACTIONS, parse_scenario, perform
from pymotoros.errors import ConfigError, PymotorosError

SRC = Path(__file__).resolve().parents[2] / "src" / "pymotoros"


@pytest.mark.parametrize(
    ("event", "message"),
    [
        (
            {"aftr_motion": 1.0, "action": "reset"},
            "events[0].aftr_motion: unknown key (did you mean 'after_motion'?); the event needs "
            "exactly one trigger of at, after_motion, when_io",
        ),
        (
            {"when_oi": {"address": 1, "value": 0}, "action": "hold", "on": True},
            "events[0].when_oi: unknown key (did you mean 'when_io'?)",
        ),
        ({"at": 1, "action": "hold", "onn": True}, "(hold).onn: unknown key for action 'hold' "
         "(its keys: on) (did you mean 'on'?)"),
        ({"at": 1, "action": "estp", "pressed": True}, "not 'estp' (did you mean 'estop'?)"),
    ],
)  # fmt: skip
def test_a_misspelt_key_is_named_with_its_nearest_valid_key(
    event: dict[str, object], message: str
) -> None:
    """Issue 20 item 10: not "found: none"."""
    with pytest.raises(ConfigError) as info:
        parse_scenario({"events": [event]})
    assert message in str(info.value)
    assert "found: none" not in str(info.value)


def test_tcp_speed_zero_is_refused_as_the_fsu_refuses_it() -> None:
    """The drift of issue 19: the scenario's range was inclusive, the FSU's is not."""
    with pytest.raises(ConfigError, match=r"\(fsu\)\.tcp_speed_mm_s: must be > 0 mm/s, not 0$"):
        parse_scenario({"events": [{"at": 0, "action": "fsu", "tcp_speed_mm_s": 0}]})
    vc = VirtualController()
    with pytest.raises(ValueError, match="must be > 0"):
        vc.set_fsu(tcp_speed_mm_s=0.0)
    parse_scenario({"events": [{"at": 0, "action": "fsu", "tcp_speed_mm_s": 0.5}]})


def test_every_declared_value_limit_is_within_what_the_controller_accepts() -> None:
    """A value the declaration accepts at its bound is not refused by the controller for
    its range (the scenario would load, then fail when its event fires)."""
    vc = VirtualController()
    spec = actions_by_name(CONTROL_ACTIONS)
    spec["fsu"].perform(vc, {"joint_speed_pct": 1})
    spec["fsu"].perform(vc, {"joint_speed_pct": 100})
    spec["fsu"].perform(vc, {"off": True})
    spec["alarm"].perform(vc, {"code": 9999, "text": "x" * 128})
    spec["error"].perform(vc, {"code": 0})
    # a rule is checked again when the action runs (an event built by hand)
    with pytest.raises(ActionParamError, match="either off = true or limits"):
        spec["fsu"].perform(vc, {"off": True, "joint_speed_pct": 50})


def test_what_the_controller_refuses_when_the_action_runs_is_our_error() -> None:
    vc = VirtualController()
    pfl = actions_by_name(CONTROL_ACTIONS)["pfl"]
    with pytest.raises(PymotorosError, match="stands still") as info:
        pfl.perform(vc, {"event": "contact"})  # PflRefusedError: our error, passed on as is
    assert isinstance(info.value, ValueError)  # a scenario's refused event is still listed


def test_every_scenario_action_is_declared_and_performed_through_its_declaration() -> None:
    declared = {s.name for s in CONTROL_ACTIONS if s.in_scenarios}
    assert set(ACTIONS) == declared
    assert {"estop", "hold", "mode", "remote", "servo", "eco", "alarm", "error", "reset",
            "io", "io_failure", "pfl", "fsu", "drop_motion"} <= declared  # fmt: skip
    assert "scenario" not in declared  # a scenario does not load another
    vc = VirtualController()
    scenario = parse_scenario(
        {"events": [{"at": 0, "action": "io_failure", "reads": True},
                    {"at": 0, "action": "error", "code": 1234, "text": "from a scenario"}]}
    )  # fmt: skip
    for event in scenario.events:
        perform(vc, event)
    assert vc.read_io_bit(20010).result_code == 1004
    assert [e.code for e in vc.snapshot().errors] == [1234]


NOT_YET: Final = {"runtime/app.py"}
"""Still probes the controller for its start-up (``motoros_started``, ``motoros_phase``:
fakes without a start-up run at once), not a reading of its state; the drop_motion hook
it probed is a constructor argument now (tests/test_wiring.py)."""


def test_nothing_outside_controller_reads_a_controller_attribute_by_getattr() -> None:
    """The pendant and the control API read the snapshot, not the controller's insides."""
    paths = sorted((SRC / "runtime").rglob("*.py")) + sorted((SRC / "cli").rglob("*.py"))
    for path in paths:
        if str(path.relative_to(SRC)) in NOT_YET:
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id in ("getattr", "hasattr")
                and node.args
                and "controller" in ast.unparse(node.args[0])
            ):
                raise AssertionError(f"{path.relative_to(SRC)}:{node.lineno}: {ast.unparse(node)}")


def test_the_safety_unit_declares_its_functions_actions_and_the_surface_takes_them() -> None:
    """A safety function's action lives with the unit that builds the function
    (``SAFETY_ACTIONS``), so a new fault needs no edit of ``actions.py``: the control
    surface takes the unit's declarations, in their order, where the OpenAPI document
    has always listed them (after io_failure)."""
    names = [s.name for s in CONTROL_ACTIONS]
    unit = [s.name for s in SAFETY_ACTIONS]
    assert unit == ["pfl", "fsu"]
    start = names.index("pfl")
    assert names[start - 1 : start + len(unit)] == ["io_failure", *unit]
    assert all(s.tag == "safety" for s in SAFETY_ACTIONS)
    vc = VirtualController()
    actions_by_name(SAFETY_ACTIONS)["fsu"].perform(vc, {"joint_speed_pct": 40})
    assert vc.snapshot().safety.fsu.joint_speed_pct == 40  # reached through target.safety


def test_an_operator_action_reaches_the_keys_which_fill_their_own_part() -> None:
    """The pendant's keys are the actions' target for a key of their own (``target.keys``)
    and fill the operator part of the snapshot themselves (no facade method, no line in
    the controller's ``snapshot()``); the snapshot still reads ``hold`` as before."""
    vc = VirtualController()
    keys = vc.keys
    toy = ActionSpec(
        "toy_hold",
        "/api/toy_hold",
        "a toy key",
        lambda t, p: t.keys.set_hold(p["on"]),
        (Param("on", "bool", "true switches HOLD on"),),
    )
    toy.perform(vc, {"on": True})
    snapshot = vc.snapshot()
    assert snapshot.operator == keys.snapshot()
    assert snapshot.operator.hold is snapshot.hold is True
