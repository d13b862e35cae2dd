"""``pymotoros sim`` configured as the image and the cluster configure it: from the
environment (``PYMOTOROS_TOKEN``, ``PYMOTOROS_SIM_HTTP_PORT``), in a subprocess, on
127.0.0.1 and OS-chosen ports. For the tests of the Dockerfile's HEALTHCHECK and of the
Prometheus scrape (tests/test_dockerfile.py, tests/test_k8s_manifests.py)."""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import selectors
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

READY_TIMEOUT_S = 60.0
STOP_TIMEOUT_S = 30.0


@dataclass(frozen=True)
class ContainerSim:
    token: str
    http: int
    """The control API's port, as the sim reported it in its ports file."""


@contextlib.contextmanager
def container_sim(
    tmp_path: Path, extra_env: dict[str, str] | None = None
) -> Iterator[ContainerSim]:
    """A twin whose token and control API port come from the environment only (the
    port 0 there: the OS picks, and the ports file says which), plus ``extra_env`` (a
    pod's other variables)."""
    token = secrets.token_urlsafe(32)
    ports_file = tmp_path / "ports.json"
    env = {
        **os.environ,
        "PYMOTOROS_TOKEN": token,
        "PYMOTOROS_SIM_HTTP_PORT": "0",
        **(extra_env or {}),
    }
    process = subprocess.Popen(  # noqa: S603 - the package's own CLI
        [sys.executable, "-m", "pymotoros", "sim", "--motion-port", "0", "--state-port", "0",
         "--io-port", "0", "--ports-file", str(ports_file)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert process.stdout is not None
        with selectors.DefaultSelector() as selector:
            selector.register(process.stdout, selectors.EVENT_READ)
            ready = selector.select(READY_TIMEOUT_S) and process.stdout.readline()
        if not ready or not ready.startswith("pymotoros sim ready"):
            process.kill()
            _out, err = process.communicate(timeout=STOP_TIMEOUT_S)
            raise AssertionError(f"pymotoros sim did not get ready: {err[-3000:]}")
        yield ContainerSim(token, json.loads(ports_file.read_text())["http"])
    finally:
        process.terminate()
        try:
            process.communicate(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()
