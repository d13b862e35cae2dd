"""Several cells in one process (runtime/fleet.py): one ticker ticks every controller in
a fixed order, each cell on its own ports, all-or-nothing start, ordered stop, a crash
anywhere stops everything, and one cell's misbehaving client leaves the others alone."""

from __future__ import annotations

import asyncio
import socket
from dataclasses import replace
from pathlib import Path

import pytest

from load_proof import Stopwatch, assert_loop_kept_time, within
from pymotoros.controller import VirtualController
from pymotoros.controller.cell import default_cell, load_cell
from pymotoros.errors import ConfigError
from pymotoros.protocol.constants import ByteOrder, MotionCommand, Port, ResultCode
from pymotoros.protocol.messages import MotoMotionReply, Ping, PingReply
from pymotoros.runtime.clock import ManualClock
from pymotoros.runtime.fleet import (
    CellPorts,
    Fleet,
    FleetCell,
    cell_names,
    check_port_clashes,
    read_cell_ports,
)
from pymotoros.runtime.ticker import IDLE_BATCH_TICKS

from .fake_controller import BrokenAtTick3, FakeController
from .peer import Peer, ctrl, start_a_far_move
from .support import LOCAL, virtual_time

OK = ResultCode.SUCCESS
BE_LOCAL = replace(LOCAL, byte_order=ByteOrder.BIG)
"""An FS100 cell's servers: big-endian (reference §1.1), loopback port 0."""

LOCKSTEP_TICKS = 250
"""One second of simulated time: enough ticks for an order or count slip to show."""

REPLY_BUDGET_S = 0.1
"""Issue 13: a request is answered within 100 ms, whatever another client does."""

STALL_BUDGET_TICKS = 125
"""Ticks the shared loop may skip over the misbehaviour test (0.5 s), as in
test_bounded_tick.py: a shared CI machine loses some; a stalled loop loses thousands."""

STATE_BUDGET_S = 0.5
"""A new state client's first message: the stream sends every 25 ms (20 cycles)."""

ROUND_TRIPS = 50
"""Requests the well-behaved client of the other cell sends while the first misbehaves."""


def _pair() -> tuple[VirtualController, VirtualController]:
    """An HC10 on a YRC1000 and an HC10 on an FS100 (big-endian)."""
    return VirtualController(), VirtualController(default_cell("fs100", "hc10"))


def _fleet(
    a: VirtualController | FakeController,
    b: VirtualController | FakeController,
    clock: ManualClock | None = None,
) -> Fleet:
    cells = [FleetCell("a", a, LOCAL), FleetCell("b", b, BE_LOCAL)]
    return Fleet(cells, clock=clock)


class _Recording(FakeController):
    def __init__(self, name: str, log: list[str], period_ms: int = 4) -> None:
        super().__init__(period_ms=period_ms)
        self.name = name
        self.log = log

    def tick(self) -> None:
        super().tick()
        self.log.append(self.name)


async def test_one_ticker_ticks_every_cell_in_order() -> None:
    log: list[str] = []
    clock = ManualClock()
    fleet = _fleet(_Recording("a", log), _Recording("b", log), clock)
    async with fleet, virtual_time(clock):
        await fleet.ticker.wait_ticks(LOCKSTEP_TICKS)
        loops = [t for t in asyncio.all_tasks() if t.get_name() == "interpolation"]
        assert len(loops) == 1  # one loop, not one per cell
        await fleet.stop()
    step = fleet.step_stats()
    assert 0.0 < step.p50 <= step.p99 <= step.max
    fleet.reset_stats()
    assert fleet.step_stats().max == 0.0
    assert fleet.tick_stats().overruns == 0
    count = fleet.ticker.count
    assert count >= LOCKSTEP_TICKS
    assert all(app.ticker is fleet.ticker for app in fleet.apps)
    assert log == ["a", "b"] * count


async def test_cells_stay_in_lockstep_and_each_listens_on_its_own_ports() -> None:
    yrc, fs100 = _pair()
    clock = ManualClock()
    fleet = _fleet(yrc, fs100, clock)
    async with fleet, virtual_time(clock):
        ports = [app.ports for app in fleet.apps]
        taken = [p for b in ports for p in (b.motion, b.state, b.io)]
        assert len(set(taken)) == len(taken)
        assert 0 not in taken
        for bound, order in zip(ports, (ByteOrder.LITTLE, ByteOrder.BIG), strict=True):
            peer = await Peer.connect(bound.motion, Port.MOTION, order)
            assert isinstance(await peer.request(Ping()), PingReply)
            assert await ctrl(peer, MotionCommand.CHECK_QUEUE_CNT) == (OK, 0)
            await peer.close()
        await fleet.ticker.wait_ticks(LOCKSTEP_TICKS)
        assert yrc.tick_count == fs100.tick_count == fleet.ticker.count
        assert fleet.apps[0].tick_stats().count == fleet.apps[1].tick_stats().count


async def test_stop_closes_every_cell_and_is_idempotent() -> None:
    fleet = _fleet(*_pair())
    async with fleet:
        peers = [
            await Peer.connect(app.ports.motion, Port.MOTION, order)
            for app, order in zip(fleet.apps, (ByteOrder.LITTLE, ByteOrder.BIG), strict=True)
        ]
        await fleet.stop()
        await fleet.stop()
        for peer, app in zip(peers, fleet.apps, strict=True):
            assert await peer.is_closed_by_server()
            with pytest.raises(OSError):
                await asyncio.open_connection("127.0.0.1", app.ports.motion)
            await peer.close()
    await fleet.wait_stopped()  # returns at once, no error


async def test_a_crashing_tick_stops_every_cell_and_propagates() -> None:
    fleet = _fleet(FakeController(), BrokenAtTick3())

    async def run() -> list[int]:
        async with asyncio.timeout(5.0), fleet:
            ports = [app.ports.motion for app in fleet.apps]
            await fleet.wait_stopped()
        return ports

    with pytest.raises(RuntimeError, match="controller bug"):
        await run()
    for port in (app.ports.motion for app in fleet.apps):
        with pytest.raises(OSError):
            await asyncio.open_connection("127.0.0.1", port)


async def test_a_port_in_use_stops_the_started_cells_and_names_the_cell() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        busy = taken.getsockname()[1]
        cells = [
            FleetCell("first", FakeController(), LOCAL),
            FleetCell("second", FakeController(), replace(LOCAL, io_port=busy)),
        ]
        fleet = Fleet(cells)
        with pytest.raises(OSError, match="cell second") as info:
            await fleet.__aenter__()
    assert info.value.errno is not None
    first = fleet.apps[0]
    assert not first.ready.is_set()  # stopped again
    with pytest.raises(OSError):
        await asyncio.open_connection("127.0.0.1", first.ports.motion)


async def test_different_periods_cannot_share_one_clock() -> None:
    with pytest.raises(ConfigError, match="different interpolation periods"):
        Fleet(
            [
                FleetCell("a", FakeController(period_ms=4), LOCAL),
                FleetCell("b", FakeController(period_ms=8), LOCAL),
            ]
        )
    with pytest.raises(ValueError, match="unique"):
        Fleet([FleetCell("a", FakeController(), LOCAL)] * 2)


async def test_a_misbehaving_client_of_one_cell_leaves_the_other_alone() -> None:
    """Cell a gets garbage, a half frame left hanging, a state reader that never reads,
    and a legal point 14,399 s away; cell b's client is answered within budget all along,
    and both controllers keep ticking in lockstep on the real clock."""
    yrc, fs100 = _pair()
    fleet = _fleet(yrc, fs100)
    async with fleet:
        a, b = (app.ports for app in fleet.apps)
        garbage = await Peer.connect(a.motion, Port.MOTION)
        await garbage.send_raw(b"\xff" * 4096)
        half = await Peer.connect(a.io, Port.IO)
        await half.send_raw(b"\x40\x00\x00\x00\x0a")  # a length prefix, then nothing
        deaf = await Peer.connect(a.state, Port.STATE)  # never reads its stream
        hostile = await Peer.connect(a.motion, Port.MOTION)
        far = await start_a_far_move(hostile)
        fleet.ticker.reset_stats()
        watch = Stopwatch()
        await hostile.send(far)

        good = await Peer.connect(b.motion, Port.MOTION, ByteOrder.BIG)
        for _ in range(ROUND_TRIPS):
            async with within(REPLY_BUDGET_S):
                assert await ctrl(good, MotionCommand.CHECK_QUEUE_CNT) == (OK, 0)
            await fleet.ticker.wait_ticks(1)
        async with within(REPLY_BUDGET_S):
            assert await hostile.message() == MotoMotionReply(0, 1, 14, OK, 0)
        assert yrc.tick_count == fs100.tick_count == fleet.ticker.count
        assert_loop_kept_time(fleet.tick_stats(), watch, STALL_BUDGET_TICKS)
        # cell a still serves a well-behaved client (on the state port: its one motion
        # slot is the hostile client's while its motion is queued, as on MotoROS)
        fresh = await Peer.connect(a.state, Port.STATE)
        async with within(STATE_BUDGET_S):
            await fresh.frame()
        for peer in (garbage, half, deaf, hostile, good, fresh):
            await peer.close()


# --------------------------------------------------------------------------- ports


def test_cell_ports_are_read_from_the_cell_file(tmp_path: Path) -> None:
    path = tmp_path / "cell.toml"
    path.write_text('[controller]\nmodel = "fs100"\n[ports]\nmotion = 51000\nhttp = 0\n')
    assert read_cell_ports(path) == CellPorts(motion=51000, http=0)
    assert load_cell(path).controller.type.value == "fs100"  # the controller skips [ports]
    plain = tmp_path / "plain.toml"
    plain.write_text('[controller]\nmodel = "fs100"\n')
    assert read_cell_ports(plain) == CellPorts()


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ("[ports]\nmotoin = 1\n", "ports.motoin: unknown key"),
        ("[ports]\nstate = 70000\n", "ports.state: must lie in 0..65535"),
        ("[ports]\nio = -1\n", "ports.io: must lie in 0..65535"),
        ('[ports]\nhttp = "8080"\n', "ports.http: must be an integer"),
        ("[ports]\nhttp = true\n", "ports.http: must be an integer"),
        ("ports = 5\n", "ports must be a table"),
    ],
)
def test_a_wrong_ports_table_is_refused_naming_the_key(
    tmp_path: Path, table: str, message: str
) -> None:
    path = tmp_path / "cell.toml"
    path.write_text(table)
    with pytest.raises(ConfigError, match=message) as info:
        read_cell_ports(path)
    assert str(path) in str(info.value)


def test_two_servers_asking_for_one_port_are_refused_naming_both() -> None:
    check_port_clashes([("a", CellPorts(motion=0, state=0)), ("b", CellPorts(motion=0))])
    check_port_clashes([("a", CellPorts(motion=5000)), ("b", CellPorts(motion=5001))])
    with pytest.raises(ConfigError, match=r"by a ports.http and by b ports.state"):
        check_port_clashes([("a", CellPorts(http=5000)), ("b", CellPorts(state=5000))])
    with pytest.raises(ConfigError, match=r"by a ports.motion and by a ports.io"):
        check_port_clashes([("a", CellPorts(motion=5000, io=5000))])


def test_cell_names_are_short_unique_tokens() -> None:
    paths = [Path("x/hc10.toml"), Path("y/hc10.toml"), Path("my cell.toml"), Path("hc10.toml")]
    assert cell_names(paths) == ["hc10", "hc10-2", "my_cell", "hc10-3"]


async def _into_a_batch(fleet: Fleet) -> None:
    """Idle for two batches, then half-way into the next (as test_ticker_batching.py)."""
    async with asyncio.timeout(10.0):
        await fleet.ticker.wait_ticks(2 * IDLE_BATCH_TICKS)
    await asyncio.sleep(IDLE_BATCH_TICKS * fleet.ticker.period / 2)


async def test_the_cells_batch_idle_ticks_only_while_nobody_observes_any_of_them() -> None:
    yrc, fs100 = _pair()
    fleet = _fleet(yrc, fs100)
    async with fleet:
        ticker = fleet.ticker
        assert all(app.idle_batching for app in fleet.apps)
        await _into_a_batch(fleet)
        assert ticker.batching
        # a client of the second cell only: the shared loop ticks every period again
        peer = await Peer.connect(fleet.apps[1].ports.state, Port.STATE, ByteOrder.BIG)
        try:
            await peer.message()
            assert not ticker.batching
            assert yrc.tick_count == fs100.tick_count == ticker.count
            deferred = ticker.batched
            async with asyncio.timeout(10.0):
                await ticker.wait_ticks(2 * IDLE_BATCH_TICKS)
            assert ticker.batched == deferred  # nothing deferred while cell b is watched
        finally:
            await peer.close()
        await _into_a_batch(fleet)
        assert ticker.batching
        assert yrc.tick_count == fs100.tick_count
