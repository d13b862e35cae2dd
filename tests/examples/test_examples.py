"""Every script in examples/ runs against ``pymotoros sim`` (port 0) and succeeds."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, sim_fixture

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SCRIPTS = sorted(p.name for p in EXAMPLES.glob("*.py"))
RUN_TIMEOUT_S = 120


sim = sim_fixture()


def run_example(sim: Sim, script: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env.update(
        PYMOTOROS_HOST=sim.host,
        PYMOTOROS_MOTION_PORT=str(sim.motion),
        PYMOTOROS_STATE_PORT=str(sim.state),
        PYMOTOROS_IO_PORT=str(sim.io),
    )
    return subprocess.run(  # noqa: S603 - our own example scripts
        [sys.executable, str(EXAMPLES / script), *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )


def test_every_example_is_tested() -> None:
    assert SCRIPTS == [
        "back_to_back.py",
        "io_signal.py",
        "joint_values.py",
        "naive_client.py",
        "named_poses.py",
        "recover_from_pfl.py",
    ]


def test_naive_client_is_linted(sim: Sim) -> None:
    sim_lint = sim.api("/api/lint")["findings"]
    before = {(f["code"], f["connection"]) for f in sim_lint}
    done = run_example(sim, "naive_client.py")
    assert done.returncode == 0, done.stderr
    new = [
        f for f in sim.api("/api/lint")["findings"] if (f["code"], f["connection"]) not in before
    ]
    assert {f["code"] for f in new} >= {"fragmented-message", "stale-reply", "unknown-command"}


def test_named_poses(sim: Sim) -> None:
    done = run_example(sim, "named_poses.py")
    assert done.returncode == 0, done.stderr
    for name in ("ready", "pick", "place", "upright", "home"):
        assert name in done.stdout


def test_joint_values(sim: Sim) -> None:
    done = run_example(sim, "joint_values.py")
    assert done.returncode == 0, done.stderr
    reached = done.stdout.split("reached:")[1].splitlines()[0]
    assert float(reached.split(",")[4]) == pytest.approx(-1.57, abs=1e-3)


def test_recover_from_pfl_without_a_contact_runs_through(sim: Sim) -> None:
    done = run_example(sim, "recover_from_pfl.py")
    assert done.returncode == 0, done.stderr
    assert "task done after 0 PFL recoveries" in done.stdout


def test_back_to_back(sim: Sim) -> None:
    done = run_example(sim, "back_to_back.py")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("done")


def test_io_signal(sim: Sim) -> None:
    done = run_example(sim, "io_signal.py", "--address", "10040")
    assert done.returncode == 0, done.stderr
    assert "IO 10040: 0 -> 1" in done.stdout
    assert "M010 = 1234" in done.stdout
    assert "refused before sending" in done.stdout


def test_examples_take_ports_as_arguments(sim: Sim) -> None:
    done = subprocess.run(  # noqa: S603
        [
            sys.executable,
            str(EXAMPLES / "io_signal.py"),
            *sim.cli_args(),
            "--address",
            "10041",
        ],
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )
    assert done.returncode == 0, done.stderr
