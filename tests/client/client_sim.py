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
        return [
            "--host",
            self.host,
            "--motion-port",
            str(self.motion),
            "--state-port",
            str(self.state),
            "--io-port",
            str(self.io),
        ]

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
            "--motion-port",
            "0",
            "--state-port",
            "0",
            "--io-port",
            "0",
            "--http-port",
            "0",
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
