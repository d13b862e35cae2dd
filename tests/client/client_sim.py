"""``pymotoros sim`` as a subprocess on 127.0.0.1 port 0, for the client, CLI and example tests.

Started with ``python -m pymotoros sim`` and waited for on its ready line (no sleeps);
stopped with SIGTERM, then killed if it does not go within a few seconds.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import json
import re
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest

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
