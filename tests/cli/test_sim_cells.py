"""``pymotoros sim --config a.toml --config b.toml``: several cells in one subprocess.

An HC10 on a YRC1000 and an MH5 on an FS100 (big-endian) on port 0: one ready line per
cell, both in the ports file (the first cell's ports also at the top, as a single cell's
file), a raw client drives each, one clock ticks both, SIGTERM stops both. And the usage
errors of options that name one cell.
"""

from __future__ import annotations

import json
import re
import select
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest
from click.testing import CliRunner

from pymotoros.cli.main import cli
from pymotoros.cli.session import read_ports_file
from pymotoros.cli.sim import cell_file_ports, sim
from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port, ResultCode
from pymotoros.protocol.messages import MotoReadIoBit, MotoReadIoBitReply, Ping, PingReply

from .test_sim import StateStream, Wire

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "cells"
HC10 = EXAMPLES / "hc10_yrc1000.toml"
READY = re.compile(
    r"pymotoros sim ready motion=(\d+) state=(\d+) io=(\d+) http=(\d+) cell=([A-Za-z0-9._-]+)"
)
STARTUP_TIMEOUT = 60.0
STOP_TIMEOUT = 20.0
FS100_CELL = """\
name = "MH5 on FS100"

[controller]
model = "fs100"

[robot]
model = "mh5"
"""
SERVO_ON_INPUT = 50073
"""An input every built-in IO map has (docs/io.md): the IO port answers a read of it."""


@dataclass
class Cell:
    name: str
    motion: int
    state: int
    io: int
    http: int


@contextmanager
def cells(tmp_path: Path, *configs: Path) -> Iterator[tuple[list[Cell], Path]]:
    """``pymotoros sim`` with several cells on port 0; stopped by SIGTERM at the end,
    which must exit 0 with nothing more on stdout and remove the ports file."""
    ports_file = tmp_path / "ports.json"
    stderr = tmp_path / "sim.log"
    args = [sys.executable, "-m", "pymotoros", "sim", "--ports-file", str(ports_file)]
    for config in configs:
        args += ["--config", str(config)]
    with stderr.open("w") as err:
        proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=err, text=True)  # noqa: S603
    assert proc.stdout is not None
    try:
        found: list[Cell] = []
        readable, _, _ = select.select([proc.stdout], [], [], STARTUP_TIMEOUT)
        # the ready lines are written at once, in one write: no read blocks after the first
        lines = [proc.stdout.readline() for _ in configs] if readable else [""]
        for line in lines:
            match = READY.fullmatch(line.rstrip("\n"))
            if match is None:
                pytest.fail(f"no ready line (got {line!r}); stderr:\n{stderr.read_text()}")
            *ports, name = match.groups()
            found.append(Cell(name, *(int(p) for p in ports)))
        yield found, ports_file
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=STOP_TIMEOUT) == 0, stderr.read_text()
        assert proc.stdout.read() == "", "one ready line per cell and nothing else on stdout"
        assert not ports_file.exists()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=STOP_TIMEOUT)
        proc.stdout.close()


def tick_count(client: httpx.Client) -> int:
    r = client.get("/api/state")
    assert r.status_code == 200, r.text
    count: int = r.json()["tick"]["count"]
    return count


def test_two_cells_in_one_process(tmp_path: Path) -> None:
    fs100 = tmp_path / "fs100.toml"
    fs100.write_text(FS100_CELL)
    with cells(tmp_path, HC10, fs100) as (found, ports_file):
        assert [c.name for c in found] == ["hc10_yrc1000", "fs100"]
        ports = [p for c in found for p in (c.motion, c.state, c.io, c.http)]
        assert len(set(ports)) == len(ports)

        data = json.loads(ports_file.read_text())
        first = found[0]
        assert read_ports_file(ports_file) == {  # what robot commands read: the first cell
            "motion": first.motion,
            "state": first.state,
            "io": first.io,
            "http": first.http,
        }
        assert [e["cell"] for e in data["cells"]] == ["hc10_yrc1000", "fs100"]
        assert [e["name"] for e in data["cells"]] == ["HC10 on YRC1000", "MH5 on FS100"]
        for entry, cell in zip(data["cells"], found, strict=True):
            assert (entry["motion"], entry["state"], entry["io"], entry["http"]) == (
                cell.motion,
                cell.state,
                cell.io,
                cell.http,
            )

        # each entry says what the cell is
        assert [(e["controller"], e["robots"]) for e in data["cells"]] == [
            ("yrc1000", ["hc10"]),
            ("fs100", ["mh5"]),
        ]

        # a robot command reading the ports file must be told which cell: it lists them
        result = CliRunner().invoke(cli, ["status", "--ports-file", str(ports_file)])
        assert result.exit_code == 2, result.output
        assert "2 cells (hc10_yrc1000, fs100): choose one with --cell NAME" in result.stderr
        result = CliRunner().invoke(cli, ["status", "--ports-file", str(ports_file), "--cell", "x"])
        assert result.exit_code == 2, result.output
        assert "no cell 'x' in this simulator (its cells: hc10_yrc1000, fs100)" in result.stderr
        # --cell (or PYMOTOROS_CELL) chooses; the big-endian cell needs no --controller
        for name, title in (("hc10_yrc1000", "HC10 on YRC1000"), ("fs100", "MH5 on FS100")):
            result = CliRunner().invoke(
                cli,
                ["status", "--ports-file", str(ports_file)],
                env={"PYMOTOROS_CELL": name},
            )
            assert result.exit_code == 0, result.output
            assert result.stdout.startswith(title), result.stdout
            assert "ERROR" not in result.stderr, result.stderr

        # a raw client drives each cell, in its own byte order
        for cell, order in zip(found, (ByteOrder.LITTLE, ByteOrder.BIG), strict=True):
            motion = Wire(cell.motion, Port.MOTION, order)
            assert isinstance(motion.request(Ping()), PingReply)
            assert motion.ctrl(MotionCommand.CHECK_QUEUE_CNT) == (ResultCode.SUCCESS, 0)
            state = StateStream(cell.state, order)
            assert state.status() is not None
            io = Wire(cell.io, Port.IO, order)
            reply = io.request(MotoReadIoBit(SERVO_ON_INPUT))
            assert isinstance(reply, MotoReadIoBitReply)
            for wire in (motion, state, io):
                wire.close()

        # one clock: the second cell's count lies between two readings of the first's
        with (
            httpx.Client(base_url=f"http://127.0.0.1:{found[0].http}", timeout=10) as a,
            httpx.Client(base_url=f"http://127.0.0.1:{found[1].http}", timeout=10) as b,
        ):
            before, other, after = tick_count(a), tick_count(b), tick_count(a)
            assert 0 < before <= other <= after


def test_a_fixed_port_in_a_cell_file_is_used(tmp_path: Path) -> None:
    """A cell file's [ports] fills the port flags not given (one cell); checked on the
    parsed command line, so that no test listens on a fixed port."""
    path = tmp_path / "cell.toml"
    path.write_text("[ports]\nmotion = 51000\nhttp = 0\n")
    ctx = sim.make_context("sim", ["--config", str(path), "--state-port", "0"])
    flags = (ctx.params["motion_port"], 0, ctx.params["io_port"], ctx.params["http_port"])
    assert cell_file_ports(ctx, path, flags) == (51000, 0, 50242, 0)
    ctx = sim.make_context("sim", ["--config", str(path), "--motion-port", "7"])
    flags = (7, ctx.params["state_port"], ctx.params["io_port"], ctx.params["http_port"])
    assert cell_file_ports(ctx, path, flags) == (7, 50241, 50242, 0)


def test_config_from_the_environment_is_one_path(tmp_path: Path) -> None:
    """Before several cells, PYMOTOROS_SIM_CONFIG named one file; it still does (not
    split at spaces): the file's mistake is reported, so it was the one read."""
    path = tmp_path / "my cell.toml"
    path.write_text("[ports]\nmotion = 70000\n")
    result = CliRunner().invoke(cli, ["sim"], env={"PYMOTOROS_SIM_CONFIG": str(path)})
    assert result.exit_code == 2, result.output
    assert f"{path}: ports.motion: must lie in 0..65535" in result.output.replace("\n", " ")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--controller", "fs100"], "--controller cannot be used with several --config"),
        (["--robot", "mh5"], "--robot cannot be used with several --config"),
        (["--motion-port", "5000"], "--motion-port 5000 names one server's port"),
        (["--http-port", "8081"], "[ports] http = ..."),
    ],
)
def test_options_of_one_cell_are_usage_errors_with_several(
    tmp_path: Path, extra: list[str], message: str
) -> None:
    result = CliRunner().invoke(cli, ["sim", "--config", str(HC10), "--config", str(HC10), *extra])
    assert result.exit_code == 2, result.output
    assert message in result.output


def test_one_scenario_for_several_cells_is_a_usage_error(tmp_path: Path) -> None:
    scenario = tmp_path / "scenario.toml"
    scenario.write_text('[[events]]\nt = 1.0\naction = "estop"\n')
    args = ["sim", "--config", str(HC10), "--config", str(HC10), "--scenario", str(scenario)]
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 2, result.output
    assert "POST /api/scenario" in result.output


def test_two_cells_asking_for_one_port_are_a_usage_error_naming_both(tmp_path: Path) -> None:
    a, b = tmp_path / "a.toml", tmp_path / "b.toml"
    a.write_text("[ports]\nhttp = 50999\n")
    b.write_text("[ports]\nmotion = 50999\n")
    result = CliRunner().invoke(cli, ["sim", "--config", str(a), "--config", str(b)])
    assert result.exit_code == 2, result.output
    assert "port 50999 is asked for twice" in result.output
    assert f"cell a ({a}) ports.http" in result.output
    assert f"cell b ({b}) ports.motion" in result.output


def test_port_zero_flags_are_accepted_with_several_cells(tmp_path: Path) -> None:
    """Port 0 asks for what several cells get anyway: the usual port-0 command line of a
    test script works with several --config (checked up to the start, which a bad cell
    file then stops)."""
    bad = tmp_path / "bad.toml"
    bad.write_text("[ports]\nmotion = 70000\n")
    args = ["sim", "--motion-port", "0", "--http-port", "0", "--config", str(HC10)]
    result = CliRunner().invoke(cli, [*args, "--config", str(bad)])
    assert result.exit_code == 2, result.output
    assert "ports.motion: must lie in 0..65535" in result.output
