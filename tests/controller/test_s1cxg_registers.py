"""Seed 003 Appendix A: every example of the S1CxG register output functions, and the rules.

The expected words are computed here from the snapshot (pulses, joint values) and the
kinematics with the seed's units written out, independently of models/s1cxg.py.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.errors import ConfigError
from pymotoros.kinematics import chain_for
from pymotoros.testing import twin

from .helpers import enter_traj_mode, point, send, start_at_current, tick_until

POSE = [0.1, 0.2, 1.5, 0.3, -0.4, 0.5]
"""A known HC10 pose (rad), away from zero so every value is non-trivial."""
DEG = 180.0 / math.pi
MOVE_TICKS = 150  # into the middle of a 2 s move


def _cell(table: Mapping[str, int], joints: list[float] | None = None) -> VirtualController:
    cell = cell_from_dict(
        {
            "groups": [{"robot": "hc10", "s1cxg": dict(table)}],
            "initial": {"servo": True, "joints": {"R1": joints or POSE}},
        }
    )
    vc = VirtualController(cell)
    vc.tick()
    return vc


def _m(vc: VirtualController, number: int) -> int:
    read = vc.read_mregister(number)
    return read.value


def _lo(v: int) -> int:
    return v & 0xFFFF


def _hi(v: int) -> int:
    return (v >> 16) & 0xFFFF


def _r(x: float) -> int:
    return int(math.copysign(math.floor(abs(x) + 0.5), x))


def _signed(v: int) -> int:
    return v - (1 << 32) if v & 0x8000_0000 else v


def _moving(table: Mapping[str, int]) -> VirtualController:
    vc = _cell(table)
    tick_until(vc, lambda: vc.snapshot().servo, "servo on")
    enter_traj_mode(vc)
    assert start_at_current(vc).ok
    goal = [0.5, 0.4, 1.8, 0.0, -0.1, 0.9]
    assert send(vc, 1, point(0, 2.0, goal)).ok
    for _ in range(MOVE_TICKS):
        vc.tick()
    return vc


# ----------------------------------------------------------------- 6.12.1 Cartesian position


def _joints(vc: VirtualController) -> list[float]:
    """Command joint values in float64 from the pulses (HC10: ROS order = controller order)."""
    ppu = [ax.pulses_per_unit for ax in vc.cell.groups[0].axes]
    return [p / f for p, f in zip(vc.snapshot().groups[0].command_pulse, ppu, strict=True)]


def _cartesian(vc: VirtualController) -> tuple[float, ...]:
    return chain_for("hc10").pose(_joints(vc))


def test_cartesian_example_1_command_two_bytes_mm_deg() -> None:
    table = {"208": 1, "209": 0} | {str(210 + k): 10 + k for k in range(7)}
    vc = _cell(table)
    x, y, z, rx, ry, rz = _cartesian(vc)
    expected = [_r(x * 1e3), _r(y * 1e3), _r(z * 1e3), _r(rx * DEG), _r(ry * DEG), _r(rz * DEG), 0]
    assert [_m(vc, 10 + k) for k in range(7)] == [_lo(v) for v in expected]
    assert any(v < 0 for v in expected)  # two's complement exercised


def test_cartesian_example_2_feedback_four_bytes_um_and_ten_thousandth_deg() -> None:
    table = {"217": 1, "218": 1} | {str(219 + k): 10 + 2 * k for k in range(7)}
    vc = _cell(table)
    x, y, z, rx, ry, rz = _cartesian(vc)  # at rest: feedback = command
    # 0.0001 deg as the parameter notes say (the example's "0.001 deg" is the seed's slip).
    values = [_r(x * 1e6), _r(y * 1e6), _r(z * 1e6)]
    values += [_r(a * DEG * 1e4) for a in (rx, ry, rz)] + [0]
    got = [(_m(vc, 10 + 2 * k), _m(vc, 11 + 2 * k)) for k in range(7)]
    assert got == [(_lo(v), _hi(v)) for v in values]


# ------------------------------------------------------------------ 6.12.2 pulse position


def test_pulse_example_1_command_two_bytes() -> None:
    table = {"202": 63, "203": 0, "204": 0} | {str(1090 + k): 10 + k for k in range(6)}
    vc = _cell(table)
    pulses = vc.snapshot().groups[0].command_pulse
    assert [_m(vc, 10 + k) for k in range(6)] == [_lo(p) for p in pulses]
    assert any(p < 0 for p in pulses)


def test_pulse_example_2_feedback_four_bytes() -> None:
    table = {"202": 0, "203": 63, "204": 63} | {str(1090 + k): 10 + 2 * k for k in range(6)}
    vc = _cell(table)
    pulses = vc.snapshot().groups[0].command_pulse  # at rest: feedback = command
    got = [(_m(vc, 10 + 2 * k), _m(vc, 11 + 2 * k)) for k in range(6)]
    assert got == [(_lo(p), _hi(p)) for p in pulses]


def test_pulse_resolution_offset_zero_resolution_and_both_sources() -> None:
    table = {
        "202": 0b000111,  # S, L, U command
        "203": 0b000100,  # U also feedback: outputs 0
        "1090": 20,
        "1091": 21,
        "1092": 22,
        "1100": 7,  # S: pulses / 7
        "1101": 0,  # L: resolution 0 counts as 1
        "1110": 100,  # S: + 100
        "1111": -5,
    }
    vc = _cell(table)
    s, l_, *_ = vc.snapshot().groups[0].command_pulse
    assert _m(vc, 20) == _lo(int(s / 7) + 100)
    assert _m(vc, 21) == _lo(l_ - 5)
    assert _m(vc, 22) == 0


def test_register_zero_is_never_written_and_the_later_output_wins() -> None:
    table = {
        "202": 0b11,
        "1090": 0,  # S: no output
        "1091": 30,  # L pulses to M030 ...
        "336": 1,
        "1290": 0,
        "1291": 30,  # ... then L's position in degrees, later in the table: it stays
    }
    vc = _cell(table)
    vc.write_mregister(0, 777)  # a client's value in M000 survives the outputs
    vc.tick()
    assert _m(vc, 0) == 777
    assert _m(vc, 30) == _lo(_r(POSE[1] * DEG))


def test_two_byte_output_keeps_the_lower_sixteen_bits() -> None:
    # 4-byte pulses and 2-byte pulses of the same axis: the 2-byte word is the low word.
    table = {"202": 1, "204": 1, "1090": 40, "205": 1, "1120": 42}
    vc = _cell(table, [1.0, *POSE[1:]])
    s = vc.snapshot().groups[0].command_pulse[0]
    assert abs(s) > 0xFFFF  # the value does not fit in 2 bytes
    assert _m(vc, 42) == _lo(s) == _m(vc, 40)
    assert _m(vc, 41) == _hi(s)


# --------------------------------------------------------------------- 6.12.3 TCP speed


def test_tcp_speed_example_1_command_mm_s_and_feedback_um_s() -> None:
    vc = _moving({"330": 1, "331": 10, "332": 2, "333": 11})
    tcp = vc.snapshot().groups[0].tcp
    assert tcp is not None
    assert tcp.command_speed_mm_s > 50.0
    # The snapshot works from float32 joint values (as MotoROS reports them): ±1 unit.
    assert _m(vc, 10) == pytest.approx(tcp.command_speed_mm_s, abs=1)
    fb = _m(vc, 11) | (_m(vc, 12) << 16)
    assert fb == pytest.approx(tcp.feedback_speed_mm_s * 1e3, abs=2)
    assert fb > 1000


def test_tcp_speed_agrees_with_the_pose_change() -> None:
    vc = _moving({"330": 2, "331": 50})
    before = np.array(_cartesian(vc)[:3])
    vc.tick()
    after = np.array(_cartesian(vc)[:3])
    per_tick_um_s = np.linalg.norm(after - before) * 1e6 / 0.004
    raw = _m(vc, 50) | (_m(vc, 51) << 16)
    assert raw == pytest.approx(per_tick_um_s, rel=0.02)


# -------------------------------------------------------------- 6.12.4 each axis speed


def _axis_speeds(vc: VirtualController) -> list[float]:
    """Command speed of each axis (rad/s) from two consecutive ticks' positions."""
    a = vc.snapshot().groups[0].command_pulse
    vc.tick()
    b = vc.snapshot().groups[0].command_pulse
    ppu = [ax.pulses_per_unit for ax in vc.cell.groups[0].axes]
    return [(y - x) / p / 0.004 for x, y, p in zip(a, b, ppu, strict=True)]


def test_axis_speed_example_1_command_deg_s() -> None:
    vc = _moving({"334": 1, "335": 0} | {str(1270 + k): 10 + k for k in range(6)})
    speeds = _axis_speeds(vc)
    assert [_m(vc, 10 + k) for k in range(6)] == [_lo(_r(v * DEG)) for v in speeds]
    assert any(abs(v * DEG) > 1 for v in speeds)


def test_axis_speed_example_2_feedback_ten_thousandth_deg_s() -> None:
    vc = _moving({"334": 0, "335": 2} | {str(1280 + k): 10 + 2 * k for k in range(6)})
    # Feedback speed: what JOINT_FEEDBACK reports (float32 rad/s): within one unit.
    speeds = vc.joint_feedback(0).vel[:6]
    values = [v * DEG * 1e4 for v in speeds]
    got = [_signed(_m(vc, 10 + 2 * k) | (_m(vc, 11 + 2 * k) << 16)) for k in range(6)]
    assert got == pytest.approx(values, abs=1.0)
    assert any(abs(v) > 1e4 for v in values)


# ----------------------------------------------------------- 6.12.5 each axis position


def test_axis_position_example_1_command_deg() -> None:
    vc = _cell({"336": 1, "337": 0} | {str(1290 + k): 10 + k for k in range(6)})
    q = _joints(vc)
    assert [_m(vc, 10 + k) for k in range(6)] == [_lo(_r(v * DEG)) for v in q]


def test_axis_position_example_2_feedback_ten_thousandth_deg() -> None:
    vc = _cell({"336": 0, "337": 2} | {str(1300 + k): 10 + 2 * k for k in range(6)})
    pulses = vc.snapshot().groups[0].command_pulse
    ppu = [ax.pulses_per_unit for ax in vc.cell.groups[0].axes]
    values = [_r(p / f * DEG * 1e4) for p, f in zip(pulses, ppu, strict=True)]
    got = [(_m(vc, 10 + 2 * k), _m(vc, 11 + 2 * k)) for k in range(6)]
    assert got == [(_lo(v), _hi(v)) for v in values]


def test_axis_position_words_by_hand() -> None:
    """POSE in pulses, truncated (§5.7): 0.1 × 81646.4858 = 8164.6 → 8164, 0.2 → 16329,
    1.5 × 71619.7244 = 107429.6 → 107429, 0.3 × 52998.596 = 15899.6 → 15899,
    −0.4 × 52139.159 = −20855.7 → −20855, 0.5 × 37242.257 = 18621.1 → 18621.

    Two bytes, whole degrees, rounded half away from zero: 5.73 → 6, 11.46 → 11,
    85.94 → 86, 17.19 → 17, −22.92 → −23 (65536 − 23 = 65513), 28.65 → 29.
    Four bytes, 0.0001°: 8164 / 81646.4858 rad = 5.72912° → 57291 (0, 57291);
    114589 = 1·65536 + 49053; 859432 = 13·65536 + 7464; 171881 = 2·65536 + 40809;
    −229176 → 0xFFFC80C8 = (65532, 32968); 286477 = 4·65536 + 24333."""
    vc = _cell({"336": 1, "337": 0} | {str(1290 + k): 10 + k for k in range(6)})
    assert vc.snapshot().groups[0].command_pulse == (8164, 16329, 107429, 15899, -20855, 18621)
    assert [_m(vc, 10 + k) for k in range(6)] == [6, 11, 86, 17, 65513, 29]
    vc = _cell({"336": 0, "337": 2} | {str(1300 + k): 10 + 2 * k for k in range(6)})
    got = [(_m(vc, 10 + 2 * k), _m(vc, 11 + 2 * k)) for k in range(6)]
    assert got == [(57291, 0), (49053, 1), (7464, 13), (40809, 2), (32968, 65532), (24333, 4)]


# ------------------------------------------------------------------ randomised tables


def test_randomised_pulse_and_position_tables() -> None:
    rng = np.random.default_rng(2021)
    for _ in range(25):  # bounded
        cmd_mask = int(rng.integers(0, 64))
        fb_mask = int(rng.integers(0, 64))
        size_mask = int(rng.integers(0, 64))
        table: dict[str, int] = {"202": cmd_mask, "203": fb_mask, "204": size_mask}
        regs = rng.choice(np.arange(100, 500, 2), size=6, replace=False)
        res = [int(r) for r in rng.integers(0, 50, size=6)]
        ofs = [int(o) for o in rng.integers(-1000, 1000, size=6)]
        for k in range(6):
            table[str(1090 + k)] = int(regs[k])
            table[str(1100 + k)] = res[k]
            table[str(1110 + k)] = ofs[k]
        joints = [float(v) for v in rng.uniform(-1.0, 1.0, size=6)]
        joints[2] = abs(joints[2])  # U range starts at −5°
        vc = _cell(table, joints)
        pulses = vc.snapshot().groups[0].command_pulse
        for k in range(6):
            bit = 1 << k
            if not (cmd_mask | fb_mask) & bit:
                continue
            value = 0 if cmd_mask & fb_mask & bit else int(pulses[k] / (res[k] or 1)) + ofs[k]
            assert _m(vc, int(regs[k])) == _lo(value), (table, k)
            if size_mask & bit:
                assert _m(vc, int(regs[k]) + 1) == _hi(value), (table, k)


# --------------------------------------------------------------------- over the wire


async def test_registers_over_the_io_port() -> None:
    table = {"336": 2} | {str(1290 + k): 100 + 2 * k for k in range(6)}
    cell = cell_from_dict(
        {
            "groups": [{"robot": "hc10", "s1cxg": table}],
            "initial": {"joints": {"R1": POSE}},
        }
    )
    async with twin(cell=cell) as (client, tw):
        words = [await client.read_mregister(100 + k) for k in range(12)]
        values = [_r(v * DEG * 1e4) for v in _joints(tw.controller)]
    assert words == [w for v in values for w in (_lo(v), _hi(v))]
    assert [_signed(words[2 * k] | (words[2 * k + 1] << 16)) for k in range(6)] == values


# ------------------------------------------------------------------ refused tables


@pytest.mark.parametrize(
    ("table", "problem"),
    [
        ({"999": 1}, "999: no such S1CxG parameter"),
        ({"208": "1"}, "208: must be an integer"),
        ({"208": 2}, "208: must be 0 (disable) or 1 (enable)"),
        ({"208": 1, "210": 10}, "211: is required when 208 = 1"),
        ({"330": 2, "331": 999}, "needs M1000"),
        ({"1090": 1000}, "1090: must be a register number"),
        ({"202": 64}, "202: sets a bit for an axis beyond"),
        ({"1096": 5}, "1096: names a register for axis 7"),
        ({"x": 1}, "is not an S1CxG parameter number"),
    ],
)
def test_bad_tables_are_refused_naming_the_parameter(
    table: dict[str, object], problem: str
) -> None:
    with pytest.raises(ConfigError) as info:
        cell_from_dict({"groups": [{"robot": "hc10", "s1cxg": table}]}, source="cell.toml")
    assert problem in str(info.value)
    assert "groups[0].s1cxg" in str(info.value)


def test_a_table_for_several_groups_is_refused() -> None:
    with pytest.raises(ConfigError, match="applies to one group"):
        cell_from_dict({"groups": [{"robot": "sda10f", "s1cxg": {"336": 1}}]})


def test_no_table_no_outputs() -> None:
    vc = VirtualController(cell_from_dict({"initial": {"joints": {"R1": POSE}}}))
    vc.run_ticks(3)
    assert all(_m(vc, n) == 0 for n in range(1, 100))


def test_vectorised_outputs_are_wired_like_the_reference_rules() -> None:
    """controller/registers.py's compiled path writes the words of the rule applied
    output by output (``write_outputs``, tests/oracles/s1cxg.py) for the same values, on
    random tables.

    Both sides take their scale from the same ``unit_scale``, so this checks the wiring
    (which value goes to which register, word split, truncation path), not the units:
    those are pinned by the examples above and, with written-out numbers, by
    :func:`test_axis_position_words_by_hand`."""
    from oracles.s1cxg import GroupValues, write_outputs
    from pymotoros.controller.io_image import mregister_words
    from pymotoros.controller.registers import RegisterOutputs, _Plan
    from pymotoros.models.s1cxg import parse_s1cxg

    rng = np.random.default_rng(7)
    for _ in range(20):  # bounded
        table: dict[str, int] = {}
        for p in ("330", "332", "334", "335", "336", "337"):
            table[p] = int(rng.integers(0, 3))
        table["331"], table["333"] = (int(v) for v in rng.integers(1, 40, size=2))
        for base in (1270, 1280, 1290, 1300):
            for k in range(6):
                table[str(base + k)] = int(rng.integers(0, 40))
        table |= {"217": 1, "218": int(rng.integers(0, 2))}
        table |= {str(219 + k): int(rng.integers(0, 40)) for k in range(7)}
        table |= {"202": int(rng.integers(0, 64)), "203": int(rng.integers(0, 64))}
        table |= {"204": int(rng.integers(0, 64))}
        table |= {str(1090 + k): int(rng.integers(0, 40)) for k in range(6)}
        table |= {str(1100 + k): int(rng.integers(0, 9)) for k in range(6)}
        table |= {str(1110 + k): int(rng.integers(-50, 50)) for k in range(6)}
        vc = _moving(table)
        parsed = parse_s1cxg(table, num_axes=6)
        outputs = RegisterOutputs(vc.cell, mregister_words(), vc._tcp, 4)
        plan = _Plan(vc.cell, 0, parsed)
        v = outputs.values(plan, vc._servos[0], 0, vc.tick_count, True).tolist()
        n = 6
        values = GroupValues(
            cartesian_command=v[0:7],
            cartesian_feedback=v[7:14],
            axis_position_command=v[14 : 14 + n],
            axis_position_feedback=v[14 + n : 14 + 2 * n],
            axis_speed_command=v[14 + 2 * n : 14 + 3 * n],
            axis_speed_feedback=v[14 + 3 * n : 14 + 4 * n],
            tcp_speed_command=v[14 + 4 * n],
            tcp_speed_feedback=v[15 + 4 * n],
            pulse_command=[int(x) for x in v[16 + 4 * n : 16 + 5 * n]],
            pulse_feedback=[int(x) for x in v[16 + 5 * n : 16 + 6 * n]],
            linear=[False] * n,
        )
        reference: dict[int, int] = {}
        write_outputs(parsed, values, reference.__setitem__)
        fast = dict(zip(plan.registers.tolist(), plan.words(np.array(v)).tolist(), strict=True))
        assert fast == reference, table


def test_outputs_at_rest_are_rewritten_every_tick() -> None:
    # At rest the values are not recomputed, but a client's write is still overwritten.
    vc = _cell({"336": 1, "1290": 10})
    expected = _m(vc, 10)
    assert expected == _lo(_r(POSE[0] * DEG))
    vc.write_mregister(10, 4321)
    vc.tick()
    assert _m(vc, 10) == expected
