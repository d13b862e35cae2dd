"""``pymotoros status`` against a twin whose control API has a token (issue 28, item 3):
the token from ``--token``, ``PYMOTOROS_TOKEN`` or the settings file; a 401 told as a
missing or wrong token with how to give it."""

from __future__ import annotations

import json
import sys
import time
import urllib.request
from pathlib import Path

from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli

TOKEN = "a-token-of-the-status-tests"  # noqa: S105 - a test token
STATUS_WAIT_S = 10.0


def status(sim: Sim, *args: str, env: dict[str, str] | None = None) -> Result:
    return CliRunner().invoke(cli, ["status", *args, *sim.cli_args()], env=env)


def post(sim: Sim, path: str, body: dict[str, object]) -> None:
    request = urllib.request.Request(
        f"http://127.0.0.1:{sim.http}{path}",
        data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json", "Authorization": f"Bearer {TOKEN}"},
        method="POST",
    )
    with urllib.request.urlopen(request, timeout=10):  # noqa: S310
        pass


def test_status_api_takes_the_token(tmp_path: Path) -> None:
    with running_sim("--token", TOKEN) as sim:
        api = f"http://127.0.0.1:{sim.http}"
        missing = status(sim, "--api", api, env={"PYMOTOROS_TOKEN": ""})
        assert missing.exit_code != 0
        assert "a token is needed and none was given (401)" in missing.output
        assert "--token TOKEN" in missing.output
        assert "PYMOTOROS_TOKEN" in missing.output
        assert "HTTP Error 401" not in missing.output
        wrong = status(sim, "--api", api, "--token", "not-the-token")
        assert wrong.exit_code != 0
        assert "the token was refused (401)" in wrong.output
        for how, env in (
            (["--token", TOKEN], {}),
            ([], {"PYMOTOROS_TOKEN": TOKEN}),
            ([], {"PYMOTOROS_TOKEN": f"{TOKEN}\n"}),  # as a Secret file gives it
        ):
            ok = status(sim, "--api", api, *how, env=env)
            assert ok.exit_code == 0, (how, env, ok.output)
            assert "PFL               idle" in ok.output
        settings = tmp_path / "pymotoros.toml"
        settings.write_text(f'token = "{TOKEN}"\n')
        from_file = status(sim, "--api", api, env={"PYMOTOROS_SETTINGS": str(settings)})
        assert from_file.exit_code == 0, from_file.output
        assert "PFL               idle" in from_file.output


def test_status_reads_the_alarm_texts_with_the_token(tmp_path: Path) -> None:
    """Without ``--api``, the alarm's text comes from the control API the ports file
    names: with the token too."""
    ports = tmp_path / "ports.json"
    with running_sim("--token", TOKEN, "--ports-file", str(ports)) as sim:
        post(sim, "/api/alarm", {"code": 4107, "subcode": 2, "text": "OUT OF RANGE (ABSO DATA)"})
        deadline = time.monotonic() + STATUS_WAIT_S
        while True:  # the state port shows the alarm at its next monitor read
            args = ["status", "--ports-file", str(ports), "--token", TOKEN]
            table = CliRunner().invoke(cli, args)
            if "OUT OF RANGE (ABSO DATA)" in table.output or time.monotonic() > deadline:
                break
        assert "4107 OUT OF RANGE (ABSO DATA)" in table.output, table.output


def test_status_says_why_the_alarm_text_is_missing(tmp_path: Path) -> None:
    """The control API refuses the alarm texts (here 401: no token): the table shows the
    alarm number, and stderr says why its text is missing and how to give the token."""
    ports = tmp_path / "ports.json"
    with running_sim("--token", TOKEN, "--ports-file", str(ports)) as sim:
        post(sim, "/api/alarm", {"code": 4107, "subcode": 2, "text": "OUT OF RANGE (ABSO DATA)"})
        deadline = time.monotonic() + STATUS_WAIT_S
        while True:  # the state port shows the alarm at its next monitor read
            args = ["status", "--ports-file", str(ports)]
            table = CliRunner().invoke(cli, args, env={"PYMOTOROS_TOKEN": ""})
            if "4107" in table.stdout or time.monotonic() > deadline:
                break
        assert "4107 (text on the pendant)" in table.stdout, table.output
        assert "alarm texts not read" in table.stderr, table.output
        assert "a token is needed and none was given (401)" in table.stderr
        assert table.stderr.count("alarm texts not read") == 1
