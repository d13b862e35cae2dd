"""What the CLI makes of the client's tagged log records (``pymotoros.log_tags``): a note
is a plain ``note: …`` line, a stop the CLI reports itself is not said twice, anything
else stays a timestamped log line (issue 29)."""

from __future__ import annotations

import logging
import re
import sys
from pathlib import Path

import pytest

from pymotoros.cli.main import configure_logging
from pymotoros.log_tags import AS_NOTE, AS_STOP_REPORT

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import running_sim


def test_a_note_is_a_plain_line_and_a_stop_report_is_left_to_the_cli(
    capsys: pytest.CaptureFixture[str],
) -> None:
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    configure_logging(0, False)  # its handler writes to the captured stderr
    try:
        log = logging.getLogger("pymotoros.client.avoid")
        log.warning("this move only takes it away, so it is allowed", extra=AS_NOTE)
        logging.getLogger("pymotoros.client.streaming").warning(
            "the move was cancelled: the robot was stopped (STOP_MOTION) and stands at [0.1] rad",
            extra=AS_STOP_REPORT,
        )
        log.warning("an ordinary warning")
    finally:
        root.handlers[:] = handlers
        root.setLevel(level)
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "note: this move only takes it away, so it is allowed"
    assert len(lines) == 2, lines  # the stop report is dropped
    assert re.fullmatch(
        r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3} WARNING pymotoros\.client\.avoid: "
        r"an ordinary warning",
        lines[1],
    )


def test_a_second_motion_client_is_told_once_by_the_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The loss of a motion connection MotoROS closed before its first reply fails the
    waiting request with the same words, which the CLI prints as ``error: …``."""
    from pymotoros.client.errors import SECOND_MOTION_CLIENT

    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    configure_logging(0, False)
    try:
        log = logging.getLogger("pymotoros.client.connection")
        log.warning("motion connection to 127.0.0.1:1 lost: %s", SECOND_MOTION_CLIENT)
        log.warning("state connection to 127.0.0.1:2 lost: closed by the controller")
    finally:
        root.handlers[:] = handlers
        root.setLevel(level)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1, lines
    assert lines[0].endswith("state connection to 127.0.0.1:2 lost: closed by the controller")


def test_a_slowed_move_ends_with_notes_on_stderr_and_the_result_on_stdout() -> None:
    """The FSU scenario slows a move: the following monitor's note during the move and
    the summary after it are ``note: …`` lines on stderr; stdout holds the result."""
    from click.testing import CliRunner

    from pymotoros.cli.main import cli

    scenario = Path(__file__).parents[2] / "examples" / "scenarios" / "fsu_long_move.toml"
    with running_sim("--scenario", str(scenario)) as sim:
        run = CliRunner().invoke(
            cli, ["move", "2.5", "0", "0", "0", "0", "0", "--enable", *sim.cli_args()]
        )
    assert run.exit_code == 0, run.output
    assert run.stdout.startswith("reached [2.5000, "), run.stdout
    assert "note" not in run.stdout
    notes = [ln for ln in run.stderr.splitlines() if ln.startswith("note: the robot ")]
    assert any("behind the plan at " in n and "slowing it" in n for n in notes), run.stderr
    assert notes[-1].startswith("note: the robot ran up to "), run.stderr
    assert notes[-1].endswith("(a safety speed limit, an override or HOLD slowed it)")
    assert "WARNING" not in run.stderr, run.stderr
