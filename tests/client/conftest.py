"""Fixtures of the client tests: the client paired in memory with a virtual controller.

``pair`` is :func:`pymotoros.testing.twin` (HC10 on a YRC1000): the real controller and
MotoROS server handlers, in virtual time, so that seconds of motion take milliseconds.
"""

from __future__ import annotations

import os
from collections.abc import AsyncIterator
from pathlib import Path

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


SCREENSHOT_DIR_ENV = "PYMOTOROS_SCREENSHOT_DIR"
"""Where the browser tests' screenshots go when set (tools/pendant_screenshots.py)."""


@pytest.fixture
def screenshot_dir(tmp_path: Path) -> Path:
    """``$PYMOTOROS_SCREENSHOT_DIR`` when set, else a temporary directory: a test run
    never writes into the checkout."""
    chosen = os.environ.get(SCREENSHOT_DIR_ENV)
    return Path(chosen) if chosen else tmp_path
