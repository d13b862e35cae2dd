"""State port (50241): cycle contents and sizes, rhythm, four slots, slow readers (§2.2-2.6)."""

from __future__ import annotations

import asyncio
import itertools
import logging
import socket
import statistics
import struct
from collections.abc import AsyncIterator

import pytest

from pymotoros.controller import VirtualController, default_cell
from pymotoros.protocol.constants import CommType, MsgType, Port, ReplyType
from pymotoros.protocol.messages import JointFeedback, RobotStatus
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.clock import ManualClock
from pymotoros.runtime.state_server import STATE_WRITE_HIGH_WATER

from .fake_controller import FakeController
from .peer import Peer
from .support import LOCAL, virtual_time


@pytest.fixture
async def fake_vapp(fake: FakeController, clock: ManualClock) -> AsyncIterator[SimulatorApp]:
    """The stand-in controller (its feedback changes every tick) on virtual time."""
    async with SimulatorApp(fake, LOCAL, clock=clock) as sim, virtual_time(clock):
        yield sim


async def state_peer(app: SimulatorApp) -> Peer:
    return await Peer.connect(app.ports.state, Port.STATE)


async def test_single_group_cycle_is_feedback_then_status(app: SimulatorApp) -> None:
    peer = await state_peer(app)
    frames = [await peer.frame() for _ in range(6)]
    start = next(i for i, f in enumerate(frames) if f.msg_type == MsgType.JOINT_FEEDBACK)
    cycle = frames[start : start + 2]
    assert [(f.msg_type, f.size) for f in cycle] == [(15, 148), (13, 44)]
    for f in frames:
        assert (f.comm_type, f.reply_type) == (CommType.TOPIC, ReplyType.INVALID)
    await peer.close()


async def test_four_groups_add_feedback_ex() -> None:
    sda = VirtualController(default_cell("yrc1000", "sda10f"))
    assert sda.num_groups == 4
    async with SimulatorApp(sda, LOCAL) as sim:
        peer = await state_peer(sim)
        frames = [await peer.frame() for _ in range(12)]
        start = next(i for i, f in enumerate(frames) if f.msg_type == MsgType.JOINT_FEEDBACK)
        sizes = [(f.msg_type, f.size) for f in frames[start : start + 6]]
        assert sizes == [(15, 148)] * 4 + [(2017, 548), (13, 44)]
        await peer.close()


async def test_cycle_every_25_ms_messages_1_ms_apart(
    vapp: SimulatorApp, clock: ManualClock
) -> None:
    peer = await state_peer(vapp)
    stamps: list[tuple[int, float]] = []
    for _ in range(40):
        frame = await peer.frame()
        stamps.append((frame.msg_type, clock.now()))
    feedback = [t for kind, t in stamps if kind == MsgType.JOINT_FEEDBACK]
    periods = [b - a for a, b in itertools.pairwise(feedback)]
    assert statistics.median(periods) == pytest.approx(0.025, abs=1e-3)
    gaps = [
        b[1] - a[1]
        for a, b in itertools.pairwise(stamps)
        if a[0] == MsgType.JOINT_FEEDBACK and b[0] == MsgType.ROBOT_STATUS
    ]
    assert gaps
    assert statistics.median(gaps) == pytest.approx(0.001, abs=5e-4)
    await peer.close()


async def test_four_slots_then_replace_slot_0_or_refuse(
    app: SimulatorApp, controller: VirtualController, monkeypatch: pytest.MonkeyPatch
) -> None:
    peers = [await state_peer(app) for _ in range(4)]
    for p in peers:
        await p.frame()
    assert controller.read_io_bit(11125).value == 1  # OT#894: state clients connected
    fifth = await state_peer(app)
    await fifth.frame()
    # slot 0 (the first client) was closed for the newcomer; its buffered frames may remain
    async with asyncio.timeout(5.0):
        while await peers[0].reader.read(4096):
            pass
    assert app.state.replaced == 1
    monkeypatch.setattr(controller, "has_queued_motion", lambda: True)  # as if moving
    sixth = await state_peer(app)
    assert await sixth.is_closed_by_server()
    assert app.state.refused == 1
    for p in [*peers, fifth, sixth]:
        await p.close()


async def test_slow_reader_gets_latest_state_not_a_backlog(
    fake_vapp: SimulatorApp, fake: FakeController
) -> None:
    vapp = fake_vapp
    raw = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    raw.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    raw.setblocking(False)
    await asyncio.get_running_loop().sock_connect(raw, ("127.0.0.1", vapp.ports.state))
    # a small StreamReader limit: the client stops reading its socket almost at once
    reader, writer = await asyncio.open_connection(sock=raw, limit=512)
    peer = Peer(reader, writer, Port.STATE, vapp.config.byte_order)
    # 10 s of controller time while the client reads nothing
    async with asyncio.timeout(30.0):
        await vapp.ticker.wait_ticks(2500)
    [client] = vapp.state._clients.values()
    buffered = client.conn.writer.transport.get_write_buffer_size()
    assert buffered <= STATE_WRITE_HIGH_WATER + 200
    # the kernel buffers absorb some cycles; most of the 400 were replaced, not queued
    assert client.dropped > 200
    # now read: a bounded number of stale frames, then fresh state
    ticks_now = fake.ticks
    for _ in range(400):  # bounded by the socket buffers, whatever the stall
        msg = await peer.message()
        if isinstance(msg, JointFeedback) and msg.pos[0] >= (ticks_now - 100) * 1e-3:
            break
    else:
        pytest.fail("no fresh feedback within 400 frames")
    assert isinstance(await peer.message(), RobotStatus)
    await peer.close()


async def test_client_reset_is_not_an_error(
    app: SimulatorApp, caplog: pytest.LogCaptureFixture
) -> None:
    peer = await state_peer(app)
    await peer.frame()
    sock = peer.writer.get_extra_info("socket")
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # close = RST
    handlers = list(app.state._tasks.values())
    with caplog.at_level(logging.INFO, logger="pymotoros.runtime"):
        await peer.close()
        done, _ = await asyncio.wait(handlers, timeout=5.0)
    assert len(done) == 1
    assert app.state.clients == 0
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR]
