"""``pymotoros replay``: a recorded CLI session replayed against fresh twins, and the diff."""

from __future__ import annotations

import json
import socket
import sys
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import running_sim

from pymotoros.cli.main import cli
from pymotoros.cli.replay import EXIT_CONNECTION, EXIT_DIFFERS, EXIT_MATCH, EXIT_USAGE
from pymotoros.client.recorder import SessionRecorder
from pymotoros.client.recording import read_recording
from pymotoros.client.replay_plan import replay_plan
from pymotoros.protocol.constants import ByteOrder, ResultCode
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionReply

GOAL = ("0.3", "0", "0", "0", "0", "0")
"""Where the recorded session moves the HC10 (rad): from the default start, all zeros."""

OFFSET_CELL = """\
[controller]
model = "yrc1000"

[[groups]]
robot = "hc10"

[initial.joints]
R1 = [0.05, 0.0, 0.0, 0.0, 0.0, 0.0]
"""
"""The recorded cell but for the start position: J1 0.05 rad (4082 pulses) away."""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A `move --enable` and an `io read`, recorded by the client (--record) and by the
    twin (sim --record), against a sim on OS-chosen ports."""
    root = tmp_path_factory.mktemp("replay")
    paths = {
        "move": root / "move.pcapng",
        "io": root / "io.pcapng",
        "sim": root / "sim.pcapng",
    }
    with running_sim("--record", str(paths["sim"])) as sim:
        for args, pcap in (
            (["move", "--enable", *GOAL], paths["move"]),
            (["io", "read", "10010"], paths["io"]),
        ):
            result = CliRunner().invoke(
                cli, [*args, "--record", str(pcap), *sim.cli_args()], catch_exceptions=False
            )
            assert result.exit_code == 0, result.output
    return paths


def _replay(*args: str) -> Result:
    return CliRunner().invoke(cli, ["replay", *args], catch_exceptions=False)


def _json(result: Result) -> dict[str, Any]:
    data: dict[str, Any] = json.loads(result.stdout)
    return data


def test_replay_against_a_fresh_twin_gives_an_empty_diff(recorded: dict[str, Path]) -> None:
    result = _replay(str(recorded["move"]), "--json")
    assert result.exit_code == EXIT_MATCH, result.output
    data = _json(result)
    assert data["match"] is True
    assert data["differences"] == []
    # START_TRAJ_MODE, the points (BUSY resends folded in), CHECK_QUEUE_CNT at least
    points = [t for t in data["timing"]["requests"] if t["request_type"] == "JOINT_TRAJ_PT_FULL"]
    assert len(points) >= 2
    assert data["requests"] == len(data["timing"]["requests"])
    assert all(t["replayed_delay_s"] is not None for t in data["timing"]["requests"])
    (group,) = data["final_positions"]
    assert group["match"] is True
    assert group["replayed"][0] == pytest.approx(float(GOAL[0]), abs=group["tolerance"][0])
    assert data["settled"] is True

    human = _replay(str(recorded["move"]))
    assert human.exit_code == EXIT_MATCH
    assert "replies: all" in human.stdout
    assert human.stdout.rstrip().endswith("MATCH")


def test_timing_beyond_the_tolerance_is_listed_not_a_difference(
    recorded: dict[str, Path],
) -> None:
    result = _replay(str(recorded["io"]), "--timing-tolerance", "1e-9", "--json")
    assert result.exit_code == EXIT_MATCH, result.output
    timing = _json(result)["timing"]
    assert timing["tolerance_s"] == 1e-9
    # no two reply delays agree to a nanosecond
    assert timing["outside_tolerance"] == [1]
    (request,) = timing["requests"]
    assert request["request_type"] == "MOTO_READ_IO_BIT"
    assert request["recorded_delay_s"] > 0
    assert request["replayed_delay_s"] > 0


def test_a_twin_side_recording_replays_too(recorded: dict[str, Path]) -> None:
    """`sim --record` holds both sessions (move, then io read): the ROS-driver pattern of
    a state port only read and a motion port of requests, plus an IO connection."""
    rec = read_recording(recorded["sim"])
    assert {c.kind.value for c in rec.connections if c.kind is not None} == {
        "motion",
        "state",
        "io",
    }
    result = _replay(str(recorded["sim"]), "--json")
    assert result.exit_code == EXIT_MATCH, result.output
    data = _json(result)
    ports = {t["port"] for t in data["timing"]["requests"]}
    assert ports == {"motion", "io"}


def test_a_different_start_position_is_the_expected_diff(
    recorded: dict[str, Path], tmp_path: Path
) -> None:
    cell = tmp_path / "offset.toml"
    cell.write_text(OFFSET_CELL)
    result = _replay(str(recorded["move"]), "--config", str(cell), "--json")
    assert result.exit_code == EXIT_DIFFERS, result.output
    data = _json(result)
    assert data["match"] is False
    first = data["differences"][0]
    assert first["request_type"] == "JOINT_TRAJ_PT_FULL"
    assert first["sequence"] == 0
    assert first["recorded"]["result"] == ResultCode.SUCCESS
    assert first["replayed"]["result"] == ResultCode.INVALID
    assert first["replayed"]["subcode"] == 3011  # DATA_START_POS: 4082 pulses away

    human = _replay(str(recorded["move"]), "--config", str(cell))
    assert human.exit_code == EXIT_DIFFERS
    assert "JOINT_TRAJ_PT_FULL sequence 0" in human.stdout
    assert "subcode 3011" in human.stdout


def test_replay_against_a_running_controller(recorded: dict[str, Path]) -> None:
    with running_sim() as sim:
        result = _replay(str(recorded["io"]), "--against", sim.host, *sim.port_args())
    assert result.exit_code == EXIT_MATCH, result.output
    assert "replies: all 1 match" in result.stdout


def test_usage_and_connection_errors(recorded: dict[str, Path], tmp_path: Path) -> None:
    text = tmp_path / "notes.pcapng"
    text.write_text("not a capture\n")
    result = _replay(str(text))
    assert result.exit_code == EXIT_USAGE
    assert "not a pcapng file" in result.output

    result = _replay(str(recorded["move"]), "--controller", "fs100")
    assert result.exit_code == EXIT_USAGE
    assert "little-endian" in result.output
    assert "big-endian" in result.output

    result = _replay(str(recorded["move"]), "--config", str(text), "--robot", "hc10")
    assert result.exit_code == EXIT_USAGE

    with socket.socket() as probe:  # a port nobody listens on: bound, never listening
        probe.bind(("127.0.0.1", 0))
        port = str(probe.getsockname()[1])
        result = _replay(str(recorded["io"]), "--against", "127.0.0.1", "--io-port", port)
    assert result.exit_code == EXIT_CONNECTION
    assert f"127.0.0.1:{port}" in result.output


def test_busy_resends_are_one_request(tmp_path: Path) -> None:
    """BUSY twice then SUCCESS for the same point: one request of three attempts, whose
    final reply is compared; the next point is another request."""
    pcap = tmp_path / "busy.pcapng"
    rec = SessionRecorder(pcap)
    flow = rec.flow(50240)
    order = ByteOrder.LITTLE
    point0 = JointTrajPtFull(0, 0, 15, 0.0, (0.0,) * 10, (0.0,) * 10, (0.0,) * 10)
    point1 = JointTrajPtFull(0, 1, 15, 0.1, (0.01,) * 10, (0.0,) * 10, (0.0,) * 10)
    for point, results in ((point0, (1, 1, 0)), (point1, (0,))):
        for result in results:
            flow.sent(encode(point, order))
            reply = MotoMotionReply(0, point.sequence, 14, result, 0, (0.0,) * 10)
            flow.received(encode(reply, order))
    rec.close()
    recording = read_recording(pcap)
    (steps,) = replay_plan(recording).values()
    assert [len(s.attempts) for s in steps] == [3, 1]
    assert [s.final_reply.message.result for s in steps if s.final_reply] == [0, 0]
    assert not steps[0].polled
