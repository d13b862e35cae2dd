"""The in-memory twin of a cell with obstacles, and a client that knows the same cell."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from typing import Any

from pymotoros.client import RobotClient
from pymotoros.controller.cell import cell_from_dict
from pymotoros.models.cell import cell_models_from_dict
from pymotoros.testing import Twin


@contextlib.asynccontextmanager
async def twin_of_cell(
    data: dict[str, Any], *, enable: bool = True
) -> AsyncIterator[tuple[RobotClient, Twin]]:
    """The twin of the cell ``data`` and a client given the same cell (so it knows the
    obstacles), connected with the first state received and, if ``enable``, enabled."""
    async with (
        Twin(cell_from_dict(data)) as the_twin,
        the_twin.client(cell=cell_models_from_dict(data)) as client,
    ):
        await client.wait_for_state()
        if enable:
            await client.enable()
        yield client, the_twin
