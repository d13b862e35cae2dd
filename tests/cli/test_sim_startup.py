"""``pymotoros sim`` with a cell whose MotoROS fails its start-up checks: ``-`` ports."""

from __future__ import annotations

import json
import re
import select
import signal
import subprocess
import sys
import urllib.request
from pathlib import Path

READY_NOT_LISTENING = re.compile(r"pymotoros sim ready motion=- state=- io=- http=(\d+)")
STARTUP_TIMEOUT = 60.0


def test_fatal_startup_alarm_prints_dashes_and_the_api_says_why(tmp_path: Path) -> None:
    cell = tmp_path / "old.toml"
    cell.write_text('[controller]\nmodel = "yrc1000"\nsoftware = "YAS2.10.00-00"\n')
    cmd = [sys.executable, "-m", "pymotoros", "sim", "--config", str(cell)]
    cmd += ["--motion-port", "0", "--state-port", "0", "--io-port", "0", "--http-port", "0"]
    with (tmp_path / "err.log").open("w") as err:
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, text=True)  # noqa: S603
    try:
        assert proc.stdout is not None
        readable, _, _ = select.select([proc.stdout], [], [], STARTUP_TIMEOUT)
        line = proc.stdout.readline() if readable else ""
        match = READY_NOT_LISTENING.fullmatch(line.rstrip("\n"))
        assert match, f"{line!r}\n{(tmp_path / 'err.log').read_text()}"
        url = f"http://127.0.0.1:{match.group(1)}/api/state"
        with urllib.request.urlopen(url, timeout=10) as r:
            doc = json.load(r)
        assert doc["ports"] == {"motion": None, "state": None, "io": None}
        assert doc["alarms"][0]["code"] == 8003
        assert doc["alarms"][0]["subcode"] == 8
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=20) == 0
        if proc.stdout is not None:
            proc.stdout.close()


def test_a_bad_scenario_file_is_refused_before_the_sim_starts(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[[events]]\nafter_motion = 1.0\naction = "pfl"\nevent = "bump"\n')
    done = subprocess.run(  # noqa: S603 - our own CLI
        [sys.executable, "-m", "pymotoros", "sim", "--scenario", str(bad), "--http-port", "0"],
        capture_output=True,
        text=True,
        timeout=STARTUP_TIMEOUT,
        check=False,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    assert "events[0] (pfl).event: must be one of contact, clamping" in done.stderr
