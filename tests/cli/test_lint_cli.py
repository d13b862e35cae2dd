"""Client lint from the command line: ``pymotoros sim --lint-report FILE`` and
``pymotoros lint RECORDING`` (issue 31), for our own CLI (no finding) and for a client
that does what a robot answers differently (findings, exit code 1)."""

from __future__ import annotations

import json
import socket
import sys
import time
from pathlib import Path

from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim

from pymotoros.cli.main import cli
from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import MotoMotionCtrl, Ping

ORDER = ByteOrder.LITTLE
"""The default cell's (HC10 on a YRC1000)."""
PIECE_GAP_S = 0.2
"""Between the two pieces of a fragmented message: the twin reads the first on its own."""


def invoke(*args: str) -> Result:
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def robot(sim: Sim, *args: str) -> Result:
    result = invoke(*args, *sim.cli_args())
    assert result.exit_code == 0, result.output
    return result


def _codes(document: dict[str, list[dict[str, object]]]) -> list[str]:
    return sorted(str(f["code"]) for f in document["findings"])


def test_our_cli_gives_no_finding_live_or_recorded(tmp_path: Path) -> None:
    report, recording = tmp_path / "lint.json", tmp_path / "session.pcapng"
    with running_sim("--lint-report", str(report), "--record", str(recording)) as sim:
        robot(sim, "enable")
        robot(sim, "move", "0.2", "0", "0", "0", "-0.5", "0")
        robot(sim, "move", "--named", "home")
        robot(sim, "io", "write", "10030", "1")
        robot(sim, "io", "read", "10030")
        robot(sim, "stop")
        assert sim.api("/api/lint") == {"findings": []}
    assert json.loads(report.read_text()) == {"findings": []}
    result = invoke("lint", str(recording))
    assert result.exit_code == 0, result.output
    assert result.output.strip() == "no client lint findings"


def _misbehave(sim: Sim) -> None:
    """A client that asks for a command MotoROS does not know, then sends a message in
    two pieces (last: on a robot the pieces put the stream out of step)."""
    with socket.create_connection((sim.host, sim.motion), timeout=10) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.sendall(
            encode(MotoMotionCtrl(0, 0, MotionCommand.CHECK_QUEUE_CNT, (0.0,) * 10), ORDER)
        )
        sock.recv(1024)
        sock.sendall(encode(MotoMotionCtrl(0, 0, 200199, (0.0,) * 10), ORDER))
        sock.recv(1024)
        ping = encode(Ping(), ORDER)
        sock.sendall(ping[:10])
        time.sleep(PIECE_GAP_S)
        sock.sendall(ping[10:])
        sock.recv(1024)


def test_a_misbehaving_client_is_reported_live_and_recorded(tmp_path: Path) -> None:
    report, recording = tmp_path / "lint.json", tmp_path / "session.pcapng"
    expected = ["fragmented-message", "stale-reply", "unknown-command"]
    with running_sim("--lint-report", str(report), "--record", str(recording)) as sim:
        _misbehave(sim)
        assert set(expected) <= set(_codes(sim.api("/api/lint")))
    written = json.loads(report.read_text())
    assert set(expected) <= set(_codes(written))
    finding = next(f for f in written["findings"] if f["code"] == "unknown-command")
    assert finding["connection"].startswith("127.0.0.1:")
    assert finding["reference"] == "§3.1"
    assert "command 200199" in finding["text"]
    table = invoke("lint", str(recording))
    assert table.exit_code == 1, table.output
    assert "3 client lint finding(s)" in table.output
    assert "fix: Send each message with one write" in table.output
    as_json = invoke("lint", str(recording), "--json")
    assert as_json.exit_code == 1
    recorded = json.loads(as_json.output)
    assert _codes(recorded) == expected
    assert {f["connection"] for f in recorded["findings"]} == {finding["connection"]}


def test_an_unreadable_recording_is_a_usage_error(tmp_path: Path) -> None:
    bogus = tmp_path / "not-a-recording.pcapng"
    bogus.write_bytes(b"hello")
    result = CliRunner().invoke(cli, ["lint", str(bogus)])
    assert result.exit_code == 2
    assert "error:" in result.output


def _point(sock: socket.socket, sequence: int, t: float, pos: float, vel: float) -> int:
    """One JOINT_TRAJ_PT_FULL for joint 1; the reply's result (BUSY resent after 5 ms)."""
    from pymotoros.protocol.framing import FrameDecoder, decode_reply
    from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionReply

    request = JointTrajPtFull.for_joints(0, sequence, t, [pos] + [0.0] * 5, [vel] + [0.0] * 5)
    while True:
        sock.sendall(encode(request, ORDER))
        decoder = FrameDecoder(ORDER)
        frame = None
        while frame is None:
            decoder.feed(sock.recv(1024))
            frame = decoder.next_frame()
        reply = decode_reply(frame, ORDER, Port.MOTION)
        assert isinstance(reply, MotoMotionReply)
        if reply.result != 1:
            return int(reply.result)
        time.sleep(0.005)


def test_a_careless_stream_is_found_live_and_in_its_recording(tmp_path: Path) -> None:
    """No state connection, a gap in the sequence, and the last point still moving: the
    twin finds all three, and ``pymotoros lint`` finds them in the recording too."""
    recording = tmp_path / "session.pcapng"
    expected = ["motion-without-state", "queue-starved", "sequence-not-consecutive"]
    with running_sim("--record", str(recording)) as sim:
        robot(sim, "enable")
        with socket.create_connection((sim.host, sim.motion), timeout=10) as sock:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            assert _point(sock, 0, 0.0, 0.0, 0.0) == 0
            assert _point(sock, 1, 0.3, 0.03, 0.1) == 0
            assert _point(sock, 3, 0.6, 0.06, 0.1) == 0  # 2 never sent; still moving
            time.sleep(1.0)  # the queue runs dry at 0.1 rad/s
        live = sim.api("/api/lint")
    assert _codes(live) == expected
    result = invoke("lint", str(recording), "--json")
    assert result.exit_code == 1, result.output
    assert _codes(json.loads(result.output)) == expected


def test_the_report_of_several_cells_names_each_findings_cell(tmp_path: Path) -> None:
    from pymotoros.cli.lint import write_lint_report
    from pymotoros.controller.lint import ClientLint, LintCode

    line1, line2 = ClientLint(), ClientLint()
    line2.record(LintCode.MOTION_WITHOUT_STATE, "10.0.0.2:4000", 3.0, "point 0")
    report = tmp_path / "lint.json"
    write_lint_report(report, [("line1", line1), ("line2", line2)])
    (finding,) = json.loads(report.read_text())["findings"]
    assert finding["cell"] == "line2"
    assert finding["code"] == "motion-without-state"
    write_lint_report(report, [(None, line2)])
    assert "cell" not in json.loads(report.read_text())["findings"][0]
