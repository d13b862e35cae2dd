"""The client reads the S1CxG register outputs with the same table as the cell."""

from __future__ import annotations

import asyncio
import math
from pathlib import Path

import pytest

from pymotoros.client.registers import s1cxg_table
from pymotoros.controller.cell import cell_from_dict, load_cell
from pymotoros.errors import ConfigError
from pymotoros.models import robot_model
from pymotoros.models.s1cxg import Source
from pymotoros.testing import twin

CELL = """
[controller]
model = "yrc1000"

[[groups]]
robot = "hc10"

[groups.s1cxg]
# TCP speed: command in mm/s at M010, feedback in um/s at M011-M012 (seed Example 1)
330 = 1
331 = 10
332 = 2
333 = 11
# Cartesian feedback position, 4 bytes, M020..M033
217 = 1
218 = 1
219 = 20
220 = 22
221 = 24
222 = 26
223 = 28
224 = 30
225 = 32
# each axis position (feedback, 4 bytes) M040..M051
337 = 2
1300 = 40
1301 = 42
1302 = 44
1303 = 46
1304 = 48
1305 = 50

[initial.joints]
R1 = [0.1, 0.2, 1.5, 0.3, -0.4, 0.5]
"""


async def test_client_decodes_tcp_pose_and_axes_from_the_cell_file(tmp_path: Path) -> None:
    path = tmp_path / "cell.toml"
    path.write_text(CELL, encoding="utf-8")
    async with twin(cell=load_cell(path)) as (client, _):
        values = await client.read_register_outputs(path)
        pose = client.tcp_pose()
        joints = client.state.positions(0)
    assert joints is not None
    assert values.tcp_speed_mm_s() == 0.0
    assert values.tcp_speed_mm_s(Source.COMMAND) == 0.0
    cart = values.cartesian()
    assert cart[:3] == pytest.approx([v * 1000 for v in pose[:3]], abs=1e-3)
    assert cart[3:6] == pytest.approx([math.degrees(v) for v in pose[3:]], abs=1e-3)
    assert cart[6] == 0.0
    assert values.axis_positions()[:6] == pytest.approx([math.degrees(v) for v in joints], abs=1e-3)
    assert values.axis_positions()[6] is None
    assert values.axis_speeds() == (None,) * 8


async def test_client_reads_the_tcp_speed_while_moving() -> None:
    table = {"330": 1, "331": 10}
    cell = cell_from_dict({"groups": [{"robot": "hc10", "s1cxg": table}]})
    async with twin(cell=cell) as (client, tw):
        await client.enable()
        seen: list[float] = []

        async def sample(_: object) -> None:
            values = await client.read_register_outputs(table)
            speed = values.tcp_speed_mm_s(Source.COMMAND)
            assert speed is not None
            seen.append(speed)

        move = asyncio.create_task(client.move_joints((0.5, 0.3, 0.5, 0.0, 0.0, 0.0)))
        for _ in range(20):  # bounded sampling while it moves
            await sample(None)
            await tw.sleep(0.05)
        await move
    assert max(seen) > 50.0


def test_a_bad_table_is_refused_by_the_client_too() -> None:
    with pytest.raises(ConfigError, match=r"s1cxg\.4242: no such S1CxG parameter"):
        s1cxg_table({"4242": 1}, robot_model("hc10").groups[0])
