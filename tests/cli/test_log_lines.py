"""What the CLI makes of the client's tagged log records (``pymotoros.log_tags``): a note
is a plain ``note: …`` line, a stop the CLI reports itself is not said twice, anything
else stays a timestamped log line (issue 29)."""

from __future__ import annotations

import asyncio
import logging
import re
import sys
from pathlib import Path

import pytest

from pymotoros.cli.main import configure_logging
from pymotoros.client.connection import FrameConnection
from pymotoros.client.errors import ConnectionLostError
from pymotoros.log_tags import AS_NOTE, AS_STOP_REPORT
from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port
from pymotoros.protocol.messages import MotoMotionCtrl, MotoMotionReply

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


def test_a_lost_connection_is_told_once_by_the_waiting_request(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A motion connection MotoROS closes before its first reply (the one-motion-client
    rule) fails the waiting request with the loss's words, which the CLI prints as its
    ``error:`` line: the client's log line about it must not say it again at the CLI's
    default level. A loss nobody waits on (the state stream) stays a warning."""

    async def close_after_the_request(
        reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        await reader.read(1)
        writer.close()

    async def close_at_once(_: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        writer.close()

    async def main() -> None:
        motion_server = await asyncio.start_server(close_after_the_request, "127.0.0.1", 0)
        state_server = await asyncio.start_server(close_at_once, "127.0.0.1", 0)
        async with motion_server, state_server:
            motion = await FrameConnection.open(
                "127.0.0.1", _port(motion_server), Port.MOTION, ByteOrder.LITTLE
            )
            with pytest.raises(ConnectionLostError, match="MotoROS takes one motion"):
                await motion.request(
                    MotoMotionCtrl(0, 0, MotionCommand.CHECK_MOTION_READY),
                    MotoMotionReply,
                    timeout_s=2.0,
                )
            state = await FrameConnection.open(
                "127.0.0.1", _port(state_server), Port.STATE, ByteOrder.LITTLE
            )
            await asyncio.wait_for(state.closed.wait(), 2.0)
            await motion.close()
            await state.close()

    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    configure_logging(0, False)
    try:
        asyncio.run(main())
    finally:
        root.handlers[:] = handlers
        root.setLevel(level)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1, lines
    assert re.search(r"WARNING pymotoros\.client\.connection: state connection .* lost", lines[0])


def _port(server: asyncio.Server) -> int:
    return int(server.sockets[0].getsockname()[1])


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
