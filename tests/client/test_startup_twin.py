"""The in-memory twin refuses connections while MotoROS's start-up checks hold it back."""

from __future__ import annotations

import pytest

from pymotoros.client.errors import ConnectError
from pymotoros.controller import cell_from_dict
from pymotoros.testing import Twin


async def test_the_twin_refuses_connections_until_motoros_starts() -> None:
    the_twin = Twin(cell_from_dict({"controller": {"parameters": {"S2C541": 1}}}))
    async with the_twin:
        client = the_twin.client(timeout_s=2.0)
        with pytest.raises(ConnectError):
            await client.connect()
        the_twin.controller.reset()
        await the_twin.clock.sleep(0.1)
        await client.connect()
        assert (await client.wait_for_state()).status is not None
        await client.close()
