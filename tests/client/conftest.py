"""Fixtures of the client tests: a fake MotoROS peer on port 0 and a client connected to it."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest
from client_peer import ClientPeer

from pymotoros.client.robot import RobotClient
from pymotoros.protocol.constants import Port


@pytest.fixture
async def peer() -> AsyncIterator[ClientPeer]:
    p = await ClientPeer().start()
    try:
        yield p
    finally:
        await p.close()


def client_for(peer: ClientPeer, **options: object) -> RobotClient:
    return RobotClient(
        "127.0.0.1",
        motion_port=peer.ports[Port.MOTION],
        state_port=peer.ports[Port.STATE],
        io_port=peer.ports[Port.IO],
        **options,  # type: ignore[arg-type]
    )


@pytest.fixture
async def client(peer: ClientPeer) -> AsyncIterator[RobotClient]:
    async with client_for(peer, timeout_s=2.0) as c:
        await c.wait_for_state()
        yield c
