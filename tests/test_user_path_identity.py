"""The user's path made cheaper, not different (issue 22, item 2).

The same client conversation runs on the in-memory twin twice: once on the fast paths
(the state cycle as clock callbacks writing directly, frames packed in one go, feedback
at rest reused) and once on the reference paths (the simulator's broadcast and sender
tasks, every frame through the validated message classes). Everything a client can
observe must be the same: every byte each connection receives, at the same virtual
time, and the commanded pulses of every tick. The conversation covers what changes the
state stream: motion at wide and dense point spacing, a STOP_MOTION mid-move, an E-stop
pressed from outside, its reset, IO and M-register traffic, a multi-group cell (its
JOINT_FEEDBACK_EX frames) and a cell with S1CxG register outputs.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from oracles.state_cycle import as_tasks
from pymotoros.client import RobotClient
from pymotoros.controller import CellConfig, default_cell
from pymotoros.controller.cell import load_cell
from pymotoros.testing import Twin

CELLS = Path(__file__).resolve().parents[1] / "examples" / "cells"


@dataclass
class Recording:
    """What the client saw: per connection, (virtual time, bytes) as the bytes arrived
    (chunks at the same instant joined), and what it sent; the pulses of every tick."""

    received: dict[str, list[tuple[float, bytes]]] = field(default_factory=dict)
    sent: dict[str, list[tuple[float, bytes]]] = field(default_factory=dict)
    pulses: list[tuple[tuple[int, ...], ...]] = field(default_factory=list)
    outcomes: list[str] = field(default_factory=list)

    @staticmethod
    def add(log: list[tuple[float, bytes]], when: float, data: bytes) -> None:
        if log and log[-1][0] == when:
            log[-1] = (when, log[-1][1] + data)
        else:
            log.append((when, bytes(data)))


def _tap(the_twin: Twin, recording: Recording) -> None:
    """Record every byte the client's connections receive and send, with the virtual time."""
    connect = the_twin.connect
    clock = the_twin.clock

    async def tapped(host: str, port: int) -> Any:
        reader, writer = await connect(host, port)
        name = f"{port}:{len([k for k in recording.received if k.startswith(f'{port}:')])}"
        received = recording.received.setdefault(name, [])
        sent = recording.sent.setdefault(name, [])
        feed = reader.feed_data
        write = writer.write

        def feed_data(data: bytes) -> None:
            Recording.add(received, clock.now(), data)
            feed(data)

        def write_data(data: bytes) -> None:
            Recording.add(sent, clock.now(), data)
            write(data)

        reader.feed_data = feed_data  # type: ignore[method-assign]
        writer.write = write_data  # type: ignore[method-assign]
        return reader, writer

    the_twin.connect = tapped  # type: ignore[method-assign]


async def _outcome(recording: Recording, what: str, action: Callable[[], Any]) -> None:
    """Run one step; its result or its error's type and text are part of the record."""
    try:
        result = await action()
    except Exception as exc:
        recording.outcomes.append(f"{what}: {type(exc).__name__}: {exc}")
    else:
        recording.outcomes.append(f"{what}: {result!r}")


async def _conversation(client: RobotClient, the_twin: Twin, rec: Recording) -> None:
    await client.wait_for_state()
    await _outcome(rec, "enable", client.enable)
    here = await client.current_positions()
    n = len(here)
    goal = [h + (0.3 if k % 2 == 0 else -0.2) for k, h in enumerate(here)]
    wide = client.plan(here, goal, speed_scale=0.3, sample_period=0.1)
    await _outcome(rec, "move 100 ms", lambda: client.execute(wide))
    back = client.plan(goal, here, speed_scale=0.5, sample_period=0.004)
    await _outcome(rec, "move 4 ms", lambda: client.execute(back))
    await _outcome(rec, "io read", lambda: client.read_io_bit(10010))
    await _outcome(rec, "io write", lambda: client.write_io_bit(10010, 1))
    await _outcome(rec, "mreg write", lambda: client.write_mregister(200, 1234))
    await _outcome(rec, "mreg read", lambda: client.read_mregister(200))
    # A move stopped half-way by the client.
    far = [h + 0.5 for h in here[:n]]
    plan = client.plan(here, far, speed_scale=0.3, sample_period=0.02)
    move = asyncio.ensure_future(client.execute(plan))
    await the_twin.sleep(plan.points[-1].time / 2)
    await _outcome(rec, "stop", client.stop)
    await _outcome(rec, "stopped move", lambda: move)
    # An E-stop pressed from outside mid-move, then reset.
    at = await client.current_positions()
    plan = client.plan(at, here, speed_scale=0.3, sample_period=0.02)
    move = asyncio.ensure_future(client.execute(plan))
    await the_twin.sleep(0.3)
    the_twin.controller.press_estop(True)
    await _outcome(rec, "estopped move", lambda: move)
    the_twin.controller.press_estop(False)
    await the_twin.sleep(0.2)
    await _outcome(rec, "reset", client.reset_alarm)
    await _outcome(rec, "servos", client.start_servos)
    await _outcome(rec, "enable again", client.enable)
    await the_twin.sleep(0.5)  # the robot at rest: cycles repeat
    await _outcome(rec, "disable", client.disable)


async def _record(cell: CellConfig, *, task_paths: bool) -> Recording:
    rec = Recording()
    the_twin = Twin(cell)
    if task_paths:  # the state cycle as tasks, its frames through the message classes
        as_tasks(the_twin)
    groups = len(cell.groups)
    the_twin.on_tick(
        lambda: rec.pulses.append(tuple(the_twin.commanded_pulses(g) for g in range(groups)))
    )
    _tap(the_twin, rec)
    async with the_twin, the_twin.client(timeout_s=2.0) as client:
        await _conversation(client, the_twin, rec)
    return rec


@pytest.mark.parametrize(
    "cell_name",
    ["hc10_yrc1000", "hc10_register_outputs", "two_hc10_dx100"],
)
async def test_the_fast_paths_give_the_client_exactly_what_the_reference_paths_give(
    cell_name: str,
) -> None:
    cell = load_cell(CELLS / f"{cell_name}.toml")
    fast = await _record(cell, task_paths=False)
    reference = await _record(cell, task_paths=True)
    assert fast.outcomes == reference.outcomes
    assert len(fast.pulses) == len(reference.pulses)
    first_difference = next(
        (k for k, (a, b) in enumerate(zip(fast.pulses, reference.pulses, strict=True)) if a != b),
        None,
    )
    assert first_difference is None, f"tick {first_difference}: commanded pulses differ"
    assert fast.sent == reference.sent
    assert fast.received.keys() == reference.received.keys()
    for name in fast.received:
        a, b = fast.received[name], reference.received[name]
        for k, (x, y) in enumerate(zip(a, b, strict=False)):
            assert x == y, f"connection {name}: chunk {k} differs at t = {x[0]} / {y[0]} s"
        assert len(a) == len(b), f"connection {name}: {len(a)} chunks vs {len(b)}"
    # The conversation did what it says: motion, a stop, an E-stop, state at rest.
    assert any("stopped move" in o for o in fast.outcomes)
    assert len({p for p in fast.pulses}) > 100  # the robot moved
    assert sum(len(v) for k, v in fast.received.items() if k.startswith("50241")) > 100


def test_default_cell_is_what_the_example_file_gives() -> None:
    """The parametrised test's first cell stands for ``twin(robot="hc10")``."""
    assert load_cell(CELLS / "hc10_yrc1000.toml").groups == default_cell().groups
