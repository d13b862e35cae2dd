"""The user script of examples/recover_from_pfl.py against a PFL contact from a scenario file.

"A PFL contact 0.5 s into the move makes my code get the typed 5011 error, then enable
again and finish the task": once over TCP against ``pymotoros sim --scenario`` (real
time), once against the in-memory twin (virtual time).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import running_sim
from test_examples import run_example

from pymotoros.controller.scenario import load_scenario
from pymotoros.testing import sync_twin

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SCENARIO = EXAMPLES / "scenarios" / "pfl_contact.toml"


def _script() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "recover_from_pfl", EXAMPLES / "recover_from_pfl.py"
    )
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_over_tcp_with_sim_scenario() -> None:
    with running_sim("--scenario", str(SCENARIO)) as sim:
        done = run_example(sim, "recover_from_pfl.py")
        assert done.returncode == 0, done.stderr
        assert "PFL contact (5011): enabling again" in done.stdout
        assert "task done after 1 PFL recoveries" in done.stdout
        events = sim.api("/api/state")["events"]
        assert [e["action"] for e in events] == ["pfl"]
        assert events[0]["event"] == "contact"


def test_in_virtual_time_with_the_twin(capsys: pytest.CaptureFixture[str]) -> None:
    script = _script()
    with sync_twin(robot="hc10") as (robot, cell):
        cell.controller.load_scenario(load_scenario(SCENARIO))
        assert script.run_task(robot) == 1
        final = robot.current_positions()
        assert max(abs(v) for v in final) < 1e-3  # the task's last goal: home
        fired = cell.controller.fired_events
        assert [f.action for f in fired] == ["pfl"]
    assert "PFL contact (5011)" in capsys.readouterr().out
