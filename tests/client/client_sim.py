"""``pymotoros sim`` as a subprocess on 127.0.0.1 port 0, for the client, CLI and example tests.

Started with ``python -m pymotoros sim`` and waited for on its ready line (no sleeps);
stopped with SIGTERM, then killed if it does not go within a few seconds.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest
from click.testing import CliRunner

from pymotoros.cli.main import cli
from pymotoros.client import SyncRobotClient

READY_TIMEOUT_S = 30.0
STOP_TIMEOUT_S = 10.0
_READY = re.compile(r"pymotoros sim ready motion=(\d+) state=(\d+) io=(\d+) http=(\d+)")


@dataclass
class Sim:
    process: subprocess.Popen[str]
    motion: int
    state: int
    io: int
    http: int
    host: str = "127.0.0.1"

    def client_options(self) -> dict[str, Any]:
        return {"motion_port": self.motion, "state_port": self.state, "io_port": self.io}

    def cli_args(self) -> list[str]:
        return ["--host", self.host, *self.port_args()]

    def port_args(self) -> list[str]:
        """``--motion-port M --state-port S --io-port I``: where a client finds it."""
        return port_options(motion=self.motion, state=self.state, io=self.io)

    def api(self, path: str, body: dict[str, Any] | None = None) -> dict[str, Any]:
        """Call the control API (POST with a body, GET without)."""
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(
            f"http://{self.host}:{self.http}{path}",
            data=data,
            headers={"Content-Type": "application/json"},
            method="GET" if body is None else "POST",
        )
        with urllib.request.urlopen(request, timeout=10) as response:  # noqa: S310
            result: dict[str, Any] = json.loads(response.read())
            return result

    def kill(self) -> None:
        """Kill the simulator at once (a controller that dies)."""
        self.process.kill()
        self.process.wait(STOP_TIMEOUT_S)


def port_options(**ports: int) -> list[str]:
    """``--NAME-port PORT`` for each of ``ports`` (motion, state, io, http), in order."""
    return [arg for name, port in ports.items() for arg in (f"--{name}-port", str(port))]


def _readline(process: subprocess.Popen[str]) -> str:
    assert process.stdout is not None
    return process.stdout.readline()


@contextlib.contextmanager
def running_sim(*extra: str) -> Iterator[Sim]:
    process = subprocess.Popen(  # noqa: S603 - our own CLI
        [
            sys.executable,
            "-m",
            "pymotoros",
            "sim",
            "--host",
            "127.0.0.1",
            *port_options(motion=0, state=0, io=0, http=0),
            *extra,
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            line = pool.submit(_readline, process).result(READY_TIMEOUT_S)
        match = _READY.search(line)
        if match is None:
            raise RuntimeError(f"pymotoros sim did not start: {line!r}")
        motion, state, io, http = (int(x) for x in match.groups())
        yield Sim(process, motion, state, io, http)
    finally:
        if process.poll() is None:
            process.terminate()
            try:
                process.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(STOP_TIMEOUT_S)
        if process.stdout is not None:
            process.stdout.close()


def sim_fixture(*args: str) -> Any:
    """A module-scoped ``sim`` fixture: ``pymotoros sim`` with ``args``, shared by the
    module's tests (one simulator start per module)."""

    @pytest.fixture(scope="module")
    def sim() -> Iterator[Sim]:
        with running_sim(*args) as sim:
            yield sim

    return sim


GOAL_2_5_RAD = ("2.5", "0", "0", "0", "0", "0")
"""Joint 1 to 2.5 rad: a move long enough to be stopped on its way."""


@dataclass
class EstoppedMove:
    """What ``pymotoros move`` did when the E-stop was pressed during its move."""

    returncode: int
    stderr: str
    rest: tuple[float, ...]
    """The first group's joints as a client saw them once the command had ended."""


def estop_a_cli_move(sim: Sim, *, moving_beyond: float, timeout_s: float) -> EstoppedMove:
    """``pymotoros move 2.5 0 0 0 0 0`` as a subprocess against ``sim``, the E-stop
    pressed once joint 1 passed ``moving_beyond`` rad; afterwards the E-stop is released
    and ``pymotoros reset`` run, so the simulator is ready for the next test."""
    process = subprocess.Popen(  # noqa: S603 - our own CLI
        [sys.executable, "-m", "pymotoros", "move", *GOAL_2_5_RAD, *sim.cli_args()],
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ},
    )
    try:
        with SyncRobotClient(**sim.client_options()) as watcher:
            watcher.wait_until(
                lambda s: (s.positions(0) or (0,))[0] > moving_beyond, 30.0, "motion"
            )
            sim.api("/api/estop", {"pressed": True})
            _, stderr = process.communicate(timeout=timeout_s)
            rest = watcher.current_positions(0)
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGKILL)
            process.communicate()
        sim.api("/api/estop", {"pressed": False})
        CliRunner().invoke(cli, ["reset", *sim.cli_args()])
    return EstoppedMove(process.returncode, stderr, tuple(rest))
