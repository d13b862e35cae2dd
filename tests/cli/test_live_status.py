"""``pymotoros status``: the real reason motion is not possible, alarm texts, redrawn frames."""

from __future__ import annotations

import io
import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.live import FrameWriter
from pymotoros.cli.main import cli
from pymotoros.protocol.constants import NotReadySubcode as Nr


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Sim, Path]]:
    ports = tmp_path_factory.mktemp("ports") / "ports.json"
    with running_sim("--ports-file", str(ports)) as s:
        yield s, ports


def status(ports: Path, *args: str) -> Result:
    result = CliRunner().invoke(cli, ["status", "--ports-file", str(ports), *args])
    assert result.exit_code == 0, result.output
    return result


def test_servo_off_reason_is_the_not_ready_meaning(sim: tuple[Sim, Path]) -> None:
    _, ports = sim
    CliRunner().invoke(cli, ["disable", "--ports-file", str(ports)])
    CliRunner().invoke(cli, ["servo", "off", "--ports-file", str(ports)])
    out = status(ports).stdout
    assert f"SERVO_OFF (5006): servo power is off (or eco mode is on); {Nr.SERVO_OFF.remedy}" in out
    data = json.loads(status(ports, "--json").stdout)
    assert data["status"]["not_ready_reason"].startswith("SERVO_OFF (5006)")


def test_estop_and_alarm_are_named_with_the_pendant_text(sim: tuple[Sim, Path]) -> None:
    the_sim, ports = sim
    the_sim.api("/api/estop", {"pressed": True})
    try:
        out = status(ports).stdout
        assert f"ESTOP (5003): emergency stop is pressed; {Nr.ESTOP.remedy}" in out
        assert "emergency stop is pressed; an operator must release" in out  # not "enable"
    finally:
        the_sim.api("/api/estop", {"pressed": False})
    the_sim.api("/api/alarm", {"code": 4107, "text": "OUT OF RANGE (ABSO DATA)"})
    try:
        out = status(ports).stdout
        assert "alarm             4107 OUT OF RANGE (ABSO DATA)" in out
        assert f"ALARM (5001): an alarm is active (4107); {Nr.ALARM.remedy}" in out
    finally:
        CliRunner().invoke(cli, ["reset", "--ports-file", str(ports)])


def test_watch_prints_a_frame_only_when_it_changes() -> None:
    out = io.StringIO()
    frames = FrameWriter(out, live=False)
    assert frames.show("a")
    assert not frames.show("a")
    assert frames.show("b")
    assert out.getvalue() == "a\nb\n"
    assert frames.shown == 2


def test_live_redraws_in_place() -> None:
    out = io.StringIO()
    frames = FrameWriter(out, live=True)
    frames.show("frame one\nsecond line")
    frames.show("frame two\nsecond line")
    frames.close()
    text = out.getvalue()
    assert "frame two" in text
    assert "\x1b[1A" in text  # cursor up: the second frame is drawn over the first
    assert text.count("frame one") == 1


def test_watch_live_from_the_command(sim: tuple[Sim, Path]) -> None:
    _, ports = sim
    result = status(ports, "--watch", "--live", "--count", "1")
    assert "motion possible" in result.stdout
    assert "\x1b[" in result.stdout
