"""The twin's public per-tick observers (``Twin.on_tick``, ``commanded_pulses``,
``executed_this_tick``): what the check-vs-twin tests record with."""

from __future__ import annotations

import asyncio

from pymotoros.testing import twin


def test_tick_hook_sees_every_tick_and_the_commanded_pulses_of_a_move() -> None:
    async def main() -> tuple[int, int, list[tuple[int, ...]], list[bool], int]:
        async with twin(robot="hc10") as (client, tw):
            await client.start_trajectory_mode()
            seen: list[tuple[int, ...]] = []
            executed: list[bool] = []
            before = tw.clock.ticks

            def hook() -> None:
                seen.append(tw.commanded_pulses(0))
                executed.append(tw.executed_this_tick())

            remove = tw.on_tick(hook)
            await client.move_joints([0.1, 0, 0, 0, 0, 0])
            ticks = tw.clock.ticks - before
            remove()
            count = len(seen)
            await tw.sleep(0.1)  # removed: no more calls
            return ticks, count, seen, executed, len(seen)

    ticks, count, seen, executed, after = asyncio.run(main())
    assert count == ticks > 0
    assert after == count
    assert seen[0] == (0,) * 8
    assert seen[-1][0] > 0  # joint_1_s (slot 0) moved by +0.1 rad
    assert any(executed)
    assert not all(executed)
    # pulses change only on ticks that executed an entry
    for k in range(1, len(seen)):
        if seen[k] != seen[k - 1]:
            assert executed[k]
