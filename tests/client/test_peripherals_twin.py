"""A pick-and-place IO handshake against a peripheral (gripper sensor), in virtual time."""

from __future__ import annotations

import pytest

from pymotoros.controller import VirtualController, cell_from_dict
from pymotoros.errors import ConfigError
from pymotoros.testing import twin

CLOSE, CLOSED, OPENED = 10010, 20010, 20011
SENSOR_DELAY_MS = 150
POLL_S = 0.004
MAX_POLLS = 500

GRIPPER = {
    "peripherals": [
        {"name": "gripper closed", "input": CLOSED, "follows": CLOSE, "delay_ms": SENSOR_DELAY_MS},
        {"name": "gripper open", "input": OPENED, "follows": CLOSE, "delay_ms": 80, "invert": True},
    ]
}


async def test_gripper_handshake_sees_the_sensor_150_ms_after_close() -> None:
    async with twin(cell=cell_from_dict(GRIPPER), timeout_s=2.0) as (client, cell):
        assert await client.read_io_bit(OPENED) == 1  # inverted: open while not closing
        assert await client.read_io_bit(CLOSED) == 0
        start = cell.clock.now()
        await client.write_io_bit(CLOSE, 1)
        for _ in range(MAX_POLLS):
            if await client.read_io_bit(CLOSED):
                break
            await cell.clock.sleep(POLL_S)
        waited_ms = (cell.clock.now() - start) * 1000
        assert SENSOR_DELAY_MS <= waited_ms <= SENSOR_DELAY_MS + 4 * POLL_S * 1000
        assert await client.read_io_bit(OPENED) == 0
        await client.write_io_bit(CLOSE, 0)
        await cell.clock.sleep(0.1)
        assert await client.read_io_bit(OPENED) == 1
        assert await client.read_io_bit(CLOSED) == 1  # not yet: 150 ms
        await cell.clock.sleep(0.1)
        assert await client.read_io_bit(CLOSED) == 0


def test_a_short_pulse_reaches_the_input_delayed_but_whole() -> None:
    vc = VirtualController(cell_from_dict(GRIPPER))
    vc.force_io(CLOSE, 1)
    vc.run_ticks(2)
    vc.force_io(CLOSE, 0)
    seen = []
    for _ in range(60):
        vc.tick()
        seen.append(vc.io.get(CLOSED))
    assert 1 in seen
    assert seen[-1] == 0


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ({"follows": CLOSE}, r"peripherals\[0\]\.input: is required"),
        ({"input": 99999, "follows": CLOSE}, r"peripherals\[0\]\.input: address 99999"),
        ({"input": CLOSED, "follows": CLOSED}, "its own input"),
        ({"input": CLOSED, "follows": CLOSE, "delay_ms": -1}, r"delay_ms: must lie in"),
        ({"input": CLOSED, "follows": CLOSE, "colour": "red"}, "unknown key"),
    ],
)
def test_bad_peripherals_are_refused_naming_the_key(entry: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        cell_from_dict({"peripherals": [entry]})
