"""pymotoros.testing: the in-memory streams, the virtual clock and the twin itself."""

from __future__ import annotations

import asyncio

import pytest

from pymotoros.client import ConnectError
from pymotoros.controller import default_cell
from pymotoros.testing import Twin, VirtualClock, memory_stream_pair, ready_queue, twin

PERIOD_S = 0.004
"""The YRC1000's interpolation period (4 ms)."""


async def test_memory_streams_carry_bytes_both_ways_and_eof() -> None:
    (ra, wa), (rb, wb) = memory_stream_pair("client", "server")
    wa.write(b"ping")
    await wa.drain()
    assert await rb.readexactly(4) == b"ping"
    wb.write(b"pong")
    assert await ra.readexactly(4) == b"pong"
    assert wa.get_extra_info("peername") == ("server", 0)
    assert wa.get_extra_info("socket") is None
    wa.close()
    await wa.wait_closed()
    assert await rb.read(10) == b""  # EOF, as after a FIN
    wb.write(b"lost")  # the peer is gone: the bytes go nowhere
    wb.close()
    await wb.wait_closed()


async def test_ready_queue_sees_the_running_loops_ready_callbacks() -> None:
    """The one reliance on asyncio's internals, pinned: a change there fails here, not
    silently in the twin's speed (the driver would fall back to settle turns)."""
    loop = asyncio.get_running_loop()
    ready = ready_queue(loop)
    assert ready is not None, f"{type(loop).__name__}: no ready queue seen"
    before = len(ready)
    handle = loop.call_soon(lambda: None)
    assert len(ready) == before + 1
    handle.cancel()
    await asyncio.sleep(0)
    assert len(ready) <= before  # the cancelled handle has been dropped


def test_ready_queue_is_none_for_a_loop_it_cannot_see_into() -> None:
    class Foreign(asyncio.AbstractEventLoop):
        pass

    assert ready_queue(Foreign()) is None


@pytest.mark.parametrize("watch_ready", [True, False])
async def test_virtual_clock_ticks_in_order_and_wakes_sleepers_after_the_tick(
    watch_ready: bool,
) -> None:
    ticks: list[float] = []
    clock = VirtualClock(period=PERIOD_S, step=lambda: ticks.append(clock.now()))
    driver = asyncio.create_task(clock.drive(watch_ready=watch_ready))
    try:
        await clock.sleep(0.010)
        assert clock.now() == pytest.approx(0.010)
        assert len(ticks) == 3  # at 0, 4 and 8 ms
        await clock.sleep_until(0.012)
        assert len(ticks) == 4  # the tick at 12 ms runs before the sleeper due with it
        assert ticks == pytest.approx([0.0, 0.004, 0.008, 0.012])
    finally:
        driver.cancel()
        with pytest.raises(asyncio.CancelledError):
            await driver


async def test_a_tick_that_wakes_someone_lets_it_run_before_the_next_tick() -> None:
    """A reply completed in tick k is seen at tick k's time, not after a batch of ticks."""
    done: asyncio.Future[float] | None = None
    ticks = 0

    def step() -> None:
        nonlocal ticks
        ticks += 1
        if ticks == 3 and done is not None:
            done.set_result(clock.now())

    clock = VirtualClock(period=PERIOD_S, step=step)
    far = asyncio.create_task(clock.sleep_until(1.0))  # ticks up to 1 s could run in a batch
    driver = asyncio.create_task(clock.drive())
    try:
        done = asyncio.get_running_loop().create_future()
        when = await done
        assert clock.now() == pytest.approx(when)
        assert when == pytest.approx(2 * PERIOD_S)
        assert ticks == 3
    finally:
        far.cancel()
        driver.cancel()
        with pytest.raises(asyncio.CancelledError):
            await driver


def test_virtual_clock_needs_period_and_step_together() -> None:
    with pytest.raises(ValueError, match="both"):
        VirtualClock(period=PERIOD_S)
    with pytest.raises(ValueError, match="positive"):
        VirtualClock(period=0.0, step=lambda: None)


def test_twin_takes_a_cell_or_model_names() -> None:
    with pytest.raises(ValueError, match="not both"):
        Twin(default_cell(), robot="hc10")
    assert Twin(robot="sda10f").robot.name == "sda10f"


async def test_only_motoros_ports_answer() -> None:
    async with Twin() as the_twin:
        client = the_twin.client(motion_port=1234)
        with pytest.raises(ConnectError, match="refused"):
            await client.connect()


async def test_runs_are_deterministic() -> None:
    """No real I/O and one clock: the same script gives the same feedback, bit for bit."""

    async def run() -> tuple[tuple[float, ...], float, int]:
        async with twin(robot="hc10") as (client, the_twin):
            await client.enable()
            result = await client.move_joints((0.2, 0.1, 0.0, 0.0, -0.5, 0.0))
            return result.final_positions, the_twin.clock.now(), result.stream.busy_replies

    assert await run() == await run()


async def test_twin_survives_the_client_leaving_and_a_new_one_connecting() -> None:
    async with Twin() as the_twin:
        for _ in range(2):
            async with the_twin.client() as client:
                await client.wait_for_state()
                await client.enable()
                await client.move_joints((0.1, 0.0, 0.0, 0.0, 0.0, 0.0))
        assert the_twin.motion.accepted == 2
