"""A state cycle that fails stops the twin and its error comes out of ``stop()``, as a
failed broadcast task's does (the twin runs the cycle as a clock callback, not a task)."""

from __future__ import annotations

import asyncio

import pytest

from oracles.state_cycle import as_tasks
from pymotoros.errors import PymotorosError
from pymotoros.testing import Twin


@pytest.mark.parametrize("task_paths", [False, True])
async def test_a_failing_state_cycle_stops_the_twin_with_its_error(task_paths: bool) -> None:
    the_twin = Twin(robot="hc10")
    if task_paths:  # the reference route: the cycle as a task (tests/oracles/state_cycle.py)
        as_tasks(the_twin, reference_frames=False)
    calls = 0

    def broken() -> tuple[bytes, ...]:
        nonlocal calls
        calls += 1
        raise RuntimeError("cycle broke")

    the_twin.state.build_cycle = broken  # type: ignore[method-assign]
    await the_twin.start()
    client = the_twin.client(timeout_s=1.0)
    await client.connect()
    try:
        with pytest.raises(PymotorosError):  # the twin closed the connections
            await asyncio.wait_for(client.wait_for_state(), 5.0)  # real seconds, bounded
    finally:
        await client.close()
    with pytest.raises(BaseException) as info:
        await the_twin.stop()
    error = info.value
    errors = list(error.exceptions) if isinstance(error, BaseExceptionGroup) else [error]
    assert [str(e) for e in errors] == ["cycle broke"]
    assert calls == 1  # one failure stops the cycles
