"""Fixtures of the client tests: the client paired in memory with a virtual controller.

``pair`` is :func:`pymotoros.testing.twin` (HC10 on a YRC1000): the real controller and
MotoROS server handlers, in virtual time, so that seconds of motion take milliseconds.
"""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest

from pymotoros.client.robot import RobotClient
from pymotoros.testing import Twin, twin


@pytest.fixture
async def pair() -> AsyncIterator[tuple[RobotClient, Twin]]:
    async with twin(robot="hc10", timeout_s=2.0) as (client, the_twin):
        yield client, the_twin


@pytest.fixture
def client(pair: tuple[RobotClient, Twin]) -> RobotClient:
    return pair[0]


@pytest.fixture
def cell(pair: tuple[RobotClient, Twin]) -> Twin:
    """The twin's side: the controller, its servers and the clock."""
    return pair[1]
