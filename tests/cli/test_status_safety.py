"""``pymotoros status`` shows PFL, FSU and the alarm texts (with --api), not only codes."""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.sim_view import safety_data, safety_lines
from pymotoros.controller import safety

STATUS_WAIT_S = 10.0


def invoke(sim: Sim, *args: str) -> Result:
    return CliRunner().invoke(cli, [*args, *sim.cli_args()], catch_exceptions=False)


def test_status_with_the_control_api_shows_pfl_fsu_and_alarm_texts() -> None:
    with running_sim() as sim:
        api = f"http://127.0.0.1:{sim.http}"
        plain = invoke(sim, "status", "--api", api)
        assert plain.exit_code == 0, plain.output
        assert "PFL               idle" in plain.output
        assert "FSU limit         off" in plain.output
        sim.api("/api/fsu", {"joint_speed_pct": 40})
        sim.api("/api/alarm", {"code": 4107, "subcode": 2, "text": "OUT OF RANGE (ABSO DATA)"})
        deadline = time.monotonic() + STATUS_WAIT_S
        while True:  # the state port shows the alarm at its next 10 ms monitor read
            table = invoke(sim, "status", "--api", api)
            if "4107/2 OUT OF RANGE (ABSO DATA)" in table.output or time.monotonic() > deadline:
                break
        assert "4107/2 OUT OF RANGE (ABSO DATA)" in table.output
        assert "FSU limit         joints 40 %" in table.output
        data = json.loads(invoke(sim, "status", "--json", "--api", api).stdout)
        assert data["fsu"] == {"joint_speed_pct": 40, "tcp_speed_mm_s": None}
        assert data["pfl"] == "idle"
        assert data["alarms"][0]["text"] == "OUT OF RANGE (ABSO DATA)"
        bad = CliRunner().invoke(cli, ["status", "--api", "ftp://x", *sim.cli_args()])
        assert bad.exit_code != 0
        assert "--api must be an http:// URL" in bad.output


def test_without_the_api_motoros_alarms_get_their_text() -> None:
    assert safety_lines(None, 8003) == [
        "  alarm text        MotoROS set-up validation failed (the subcode on the pendant "
        "says which check)"
    ]
    assert safety_lines(None, 4107) == []
    assert safety_lines(None, None) == []


def test_a_new_safety_field_gets_its_status_line_and_json_key(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The status view follows the safety unit's declared part: a field added to
    ``SafetySnapshot`` (here a toy subclass) is shown without an edit to ``sim_view``."""

    @dataclass(frozen=True, slots=True)
    class WithDoor(safety.SafetySnapshot):
        door_open: bool = False

    monkeypatch.setattr(safety, "SafetySnapshot", WithDoor)
    doc = {"alarms": [], "pfl": "idle", "fsu": None, "door_open": True, "motoros": "running"}
    assert safety_lines(doc, None) == [
        "  PFL               idle",
        "  FSU limit         off",
        "  door open         on",
    ]
    assert safety_data(doc)["door_open"] is True
    assert set(safety_data(doc)) == {"alarms", "pfl", "fsu", "door_open", "motoros"}
