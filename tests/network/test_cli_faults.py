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
from typing import Any, TypeVar

from click.testing import CliRunner

from pymotoros.cli.main import cli
from pymotoros.cli.robot import EXIT_CONNECTION
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


def test_move_exits_3_with_what_was_lost_when_the_state_stream_stalls(
    pymotoros_twin: RunningTwin,
) -> None:
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
        result = CliRunner().invoke(
            cli,
            [
                "move",
                "--host",
                "127.0.0.1",
                "--motion-port",
                str(motion.port),
                "--state-port",
                str(state.port),
                "--io-port",
                str(io.port),
                "--enable",
                "--speed-scale",
                "0.05",
                "0.3",
                "-0.2",
                "0.2",
                "0",
                "0.1",
                "0",
            ],
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
