"""Fixtures of the client tests: a fake MotoROS peer on port 0 and a client connected to it."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest
from client_peer import ClientPeer, client_for

from pymotoros.client.robot import RobotClient


@pytest.fixture
async def peer() -> AsyncIterator[ClientPeer]:
    p = await ClientPeer().start()
    try:
        yield p
    finally:
        await p.close()


@pytest.fixture
async def client(peer: ClientPeer) -> AsyncIterator[RobotClient]:
    async with client_for(peer, timeout_s=2.0) as c:
        await c.wait_for_state()
        yield c
