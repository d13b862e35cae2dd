"""``pymotoros move`` when the state stream stalls mid-move: exit code 3 and the message.

The proxies run on their own thread and loop (the CLI runs ``asyncio.run`` on the test's
thread); a hook on the motion proxy stalls the state stream once the twin has accepted
its first points, so the fault always strikes mid-move.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Coroutine, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import pytest
from click.testing import CliRunner

from pymotoros.cli.main import cli
from pymotoros.cli.session import EXIT_CONNECTION
from pymotoros.pytest_plugin import RunningTwin

from .fault_proxy import FaultProxy
from .test_network_faults import accepted_sequences

T = TypeVar("T")


class LoopThread:
    """An event loop on a daemon thread, for proxies that must outlive a blocking call."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self._thread.start()

    def run(self, coro: Coroutine[Any, Any, T]) -> T:
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout=10)

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(timeout=10)
        self.loop.close()


@contextmanager
def proxies_on_a_thread(twin: RunningTwin) -> Iterator[tuple[FaultProxy, FaultProxy, FaultProxy]]:
    thread = LoopThread()
    started: list[FaultProxy] = []
    try:
        for port in (twin.motion, twin.state, twin.io):
            started.append(thread.run(FaultProxy(twin.host, port).start()))
        yield started[0], started[1], started[2]
    finally:
        for proxy in started:
            thread.run(proxy.close())
        thread.stop()


def planned_trajectory(tmp_path: Path) -> Path:
    """A slow out-and-back trajectory from the twin's home, timed by ``pymotoros plan``."""
    way = tmp_path / "way.csv"
    way.write_text("s,l,u,r,b,t\n0,0,0,0,0,0\n0.4,0.2,0.3,0,-0.5,0\n0,0,0,0,0,0\n")
    out = tmp_path / "traj.yaml"
    result = CliRunner().invoke(cli, ["plan", str(way), "--speed-scale", "0.1", "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


@pytest.mark.parametrize("command", ["move", "run"])
def test_move_and_run_exit_3_with_what_was_lost_when_the_state_stream_stalls(
    pymotoros_twin: RunningTwin, tmp_path: Path, command: str
) -> None:
    what = (
        ["move", "--speed-scale", "0.05", "0.3", "-0.2", "0.2", "0", "0.1", "0"]
        if command == "move"
        else ["run", str(planned_trajectory(tmp_path))]
    )
    with proxies_on_a_thread(pymotoros_twin) as (motion, state, io):
        stalled = concurrent.futures.Future[None]()

        async def stall_after_points() -> None:
            await motion.wait_until(
                lambda: bool(motion.links) and len(accepted_sequences(motion.links[0])) >= 3,
                timeout_s=30,
            )
            state.stall_downstream()
            stalled.set_result(None)

        watcher = asyncio.run_coroutine_threadsafe(stall_after_points(), motion_loop(motion))
        ports = ["--motion-port", str(motion.port), "--state-port", str(state.port)]
        result = CliRunner().invoke(
            cli,
            [*what, "--host", "127.0.0.1", *ports, "--io-port", str(io.port), "--enable"],
            catch_exceptions=False,
        )
        watcher.result(timeout=5)
        assert stalled.done()
        assert result.exit_code == EXIT_CONNECTION, result.output
        assert "the state stream stalled" in result.output
        assert "points accepted by the robot" in result.output
        assert "STOP_MOTION acknowledged" in result.output
        assert "last known position [" in result.output


def motion_loop(proxy: FaultProxy) -> asyncio.AbstractEventLoop:
    """The loop the proxy was started on (its server's)."""
    assert proxy.loop is not None
    return proxy.loop
