"""Each error example documented in README.md and docs/client.md is what the code says.

The examples are read from the documents themselves; each fragment between ``…`` must
appear in the message the client raises for the same situation (0.01 rad off on
joint_5_b of an HC10 at the start of a trajectory given to ``execute()``), numbers
included.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from pymotoros.client import StartPositionError
from pymotoros.testing import twin

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = ("README.md", "docs/client.md")
START_OFFSET_RAD = 0.01
"""The documented example: joint_5_b 0.01 rad (521 pulses) away from where the robot is."""


def documented_examples(name: str) -> list[str]:
    text = (ROOT / name).read_text(encoding="utf-8")
    found = re.findall(r"`(point 0 refused:[^`]*)`", text)
    return [" ".join(example.split()) for example in found]


async def _start_position_message() -> str:
    async with twin(robot="hc10") as (client, _):
        await client.enable()
        goal = list(await client.current_positions())
        goal[4] += START_OFFSET_RAD
        with pytest.raises(StartPositionError) as info:
            await client.execute(client.plan(goal, goal))
    return str(info.value)


@pytest.mark.parametrize("document", DOCUMENTS)
async def test_documented_3011_example_is_produced_by_execute(document: str) -> None:
    examples = documented_examples(document)
    assert examples, f"{document} lost its error example"
    message = " ".join((await _start_position_message()).split())
    for example in examples:
        fragments = [f.strip() for f in example.split("…") if f.strip()]
        for fragment in fragments:
            assert fragment in message, f"{document}: {fragment!r} not in {message!r}"
        for number in re.findall(r"[+-]?\d+(?:\.\d+)?", example):
            assert number in message, f"{document}: {number} not in {message!r}"
