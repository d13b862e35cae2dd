"""``--record``: a CLI session recorded to pcapng and opened by tshark as TCP traffic."""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
from click.testing import CliRunner

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim, sim_fixture

from pymotoros.cli.main import cli

TSHARK_TIMEOUT_S = 60


sim = sim_fixture()


def _tshark() -> str:
    path = shutil.which("tshark")
    if path is None:
        reason = "tshark is not installed (.ci/run installs it: apt-get install -y tshark)"
        print(reason)
        pytest.skip(reason)
    return path


def _payloads(tshark: str, pcap: Path) -> Counter[tuple[int, int]]:
    """(source port, destination port) → number of TCP segments with payload."""
    out = subprocess.run(  # noqa: S603 - tshark found on PATH, fixed arguments
        [
            tshark,
            "-r",
            str(pcap),
            "-Y",
            "tcp.len > 0",
            "-T",
            "fields",
            "-e",
            "tcp.srcport",
            "-e",
            "tcp.dstport",
        ],
        capture_output=True,
        text=True,
        check=True,
        timeout=TSHARK_TIMEOUT_S,
    ).stdout
    counts: Counter[tuple[int, int]] = Counter()
    for line in out.splitlines():
        src, dst = line.split("\t")
        counts[int(src), int(dst)] += 1
    return counts


def test_cli_session_recorded_and_opened_by_tshark(sim: Sim, tmp_path: Path) -> None:
    tshark = _tshark()
    io_pcap = tmp_path / "io.pcapng"
    result = CliRunner().invoke(
        cli,
        ["io", "read", "10010", "--record", str(io_pcap), *sim.cli_args()],
        catch_exceptions=False,
    )
    assert result.exit_code == 0, result.output
    counts = _payloads(tshark, io_pcap)
    (client_port,) = {s for s, d in counts if d == sim.io}
    # one IO request, one reply; nothing on the other ports (the sim's real ports)
    assert counts == {(client_port, sim.io): 1, (sim.io, client_port): 1}

    stop_pcap = tmp_path / "stop.pcapng"
    result = CliRunner().invoke(
        cli, ["stop", "--record", str(stop_pcap), *sim.cli_args()], catch_exceptions=False
    )
    assert result.exit_code == 0, result.output
    counts = _payloads(tshark, stop_pcap)
    (client_port,) = {s for s, d in counts if d == sim.motion}
    # the STOP_MOTION every motion connection starts with (docs/client.md), then the stop's
    assert counts == {(client_port, sim.motion): 2, (sim.motion, client_port): 2}
    # the TCP stream is consistent: no retransmission, lost or out-of-order segment
    flags = subprocess.run(  # noqa: S603 - as above
        [tshark, "-r", str(stop_pcap), "-Y", "tcp.analysis.flags"],
        capture_output=True,
        text=True,
        check=True,
        timeout=TSHARK_TIMEOUT_S,
    ).stdout
    assert flags.strip() == ""


def test_cli_recordings_read_back(sim: Sim, tmp_path: Path) -> None:
    """The reader on a sim's random ports: which MotoROS port each was, from the traffic."""
    from pymotoros.client.recording import read_recording
    from pymotoros.protocol.constants import Port
    from pymotoros.protocol.messages import MotoMotionCtrl, MotoMotionReply, MotoReadIoBit

    io_pcap = tmp_path / "io.pcapng"
    stop_pcap = tmp_path / "stop.pcapng"
    for args, pcap in ((["io", "read", "10010"], io_pcap), (["stop"], stop_pcap)):
        result = CliRunner().invoke(
            cli, [*args, "--record", str(pcap), *sim.cli_args()], catch_exceptions=False
        )
        assert result.exit_code == 0, result.output
    (io,) = read_recording(io_pcap).on(Port.IO)
    assert io.server_port == sim.io
    assert [type(m.message) for m in io.sent()] == [MotoReadIoBit]
    (motion,) = read_recording(stop_pcap).on(Port.MOTION)
    assert motion.server_port == sim.motion
    # the connect-time STOP_MOTION (docs/client.md), then the command's own
    assert [type(m.message) for m in motion.sent()] == [MotoMotionCtrl, MotoMotionCtrl]
    assert [type(m.message) for m in motion.received()] == [MotoMotionReply, MotoMotionReply]


async def test_record_session_context_manager_records_every_port(tmp_path: Path) -> None:
    """The API: every connection opened inside ``record_session`` is recorded."""
    from pymotoros.client.recorder import record_session
    from pymotoros.testing import twin

    tshark = _tshark()
    pcap = tmp_path / "api.pcapng"
    with record_session(pcap) as recorder:
        async with twin(robot="hc10") as (client, _):
            for _ in range(3):
                await client.read_io_bit(10010)
    counts = _payloads(tshark, pcap)
    assert recorder.packets >= sum(counts.values())
    io = [(s, d) for s, d in counts if d == 50242]
    assert len(io) == 1
    (client_port, _server) = io[0]
    assert counts[client_port, 50242] == 3
    assert counts[50242, client_port] == 3
    # the state port pushes topics: recorded server → client only
    state = [(s, d) for s, d in counts if s == 50241]
    assert state
    assert all(counts[d, s] == 0 for s, d in state)


def _frames_by_connection(pcap: Path) -> dict[str, list[list[bytes]]]:
    """MotoROS port kind → per connection (in opening order), its whole frames as bytes
    with the direction in front (so a request and a reply never compare equal)."""
    from pymotoros.client.recording import read_recording

    out: dict[str, list[list[bytes]]] = {}
    for conn in read_recording(pcap).connections:
        assert conn.kind is not None
        frames = [
            m.direction.value.encode() + m.frame.msg_type.to_bytes(4) + m.frame.body
            for m in conn.messages
        ]
        out.setdefault(conn.kind.value, []).append(frames)
    return out


def test_sim_records_the_twins_side_of_every_connection(tmp_path: Path) -> None:
    """``sim --record``: what the twin read and wrote, equal to what the client recorded."""
    tshark = _tshark()
    sim_pcap = tmp_path / "sim.pcapng"
    move_pcap = tmp_path / "move.pcapng"
    io_pcap = tmp_path / "io.pcapng"
    with running_sim("--record", str(sim_pcap)) as recording_sim:
        for args, pcap in (
            (["move", "--enable", "0.1", "0", "0", "0", "0", "0"], move_pcap),
            (["io", "read", "10010"], io_pcap),
        ):
            result = CliRunner().invoke(
                cli,
                [*args, "--record", str(pcap), *recording_sim.cli_args()],
                catch_exceptions=False,
            )
            assert result.exit_code == 0, result.output
        ports = {"motion": recording_sim.motion, "state": recording_sim.state}
        ports["io"] = recording_sim.io
    # the sim has stopped (SIGTERM): its recording is closed

    twin_side = _frames_by_connection(sim_pcap)
    client_side = _frames_by_connection(move_pcap)
    for kind, conns in _frames_by_connection(io_pcap).items():
        client_side.setdefault(kind, []).extend(conns)
    assert sorted(twin_side) == ["io", "motion", "state"]
    for kind in ("motion", "io"):  # strict request/reply: the same messages, in order
        assert twin_side[kind] == client_side[kind], kind
    # the state port: the client stopped reading at some point; up to there, the same
    assert len(twin_side["state"]) == len(client_side["state"])
    for twin_frames, client_frames in zip(twin_side["state"], client_side["state"], strict=True):
        assert client_frames
        assert twin_frames[: len(client_frames)] == client_frames

    # tshark: one TCP payload per message the twin wrote or read (it writes one per message;
    # each request of this session arrived in one read)
    counts = _payloads(tshark, sim_pcap)
    for kind, port in ports.items():
        to_server = sum(c for (s, d), c in counts.items() if d == port)
        from_server = sum(c for (s, d), c in counts.items() if s == port)
        frames = [f for conn in twin_side[kind] for f in conn]
        assert to_server == sum(f.startswith(b"to_server") for f in frames), kind
        assert from_server == sum(f.startswith(b"from_server") for f in frames), kind
    assert sum(c for (s, d), c in counts.items() if d == ports["state"]) == 0
    # every payload runs between one of the sim's ports and a client's
    assert all((s not in ports.values()) == (d in ports.values()) for s, d in counts)
