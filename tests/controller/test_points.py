"""Trajectory-point validation order (reference §3.4, §3.5), SELECT_TOOL, DH, queue count."""

from __future__ import annotations

import math

import pytest

from pymotoros.controller import VirtualController, cell_from_dict
from pymotoros.protocol.constants import InvalidSubcode as Inv
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, complete, point, send, tick_until
from .states import ready, safe_cell


def reply(vc: VirtualController, seq: int, p: object) -> tuple[int, int]:
    from pymotoros.controller import PointData

    assert isinstance(p, PointData)
    o = complete(vc, vc.trajectory_point(seq, p))
    return (o.result, o.subcode)


def test_type_14_order() -> None:
    vc = ready()
    zero = [0.0] * 6
    # group before fields before time
    assert reply(vc, 0, point(1, 99999.0, zero, fields=1)) == (R.INVALID, Inv.GROUPNO)
    assert reply(vc, 0, point(-1, 0.0, zero)) == (R.INVALID, Inv.GROUPNO)
    assert reply(vc, 0, point(0, 99999.0, zero, fields=3)) == (R.INVALID, Inv.DATA_INSUFFICIENT)
    assert reply(vc, 0, point(0, 99999.0, zero, fields=15)) == (R.INVALID, Inv.DATA_TIME)
    assert reply(vc, -5, point(0, 14400.0, zero)) == (R.INVALID, Inv.DATA_TIME)
    assert reply(vc, -5, point(0, -1.0, zero)) == (R.INVALID, Inv.SEQUENCE)  # t < 0 not refused


def test_start_position_against_the_commanded_position() -> None:
    vc = ready()
    ppr = vc.cell.groups[0].axes[0].pulses_per_unit
    near = [30.5 / ppr] + [0.0] * 5
    far = [31.5 / ppr] + [0.0] * 5
    assert reply(vc, 0, point(0, 0.0, near)) == (R.SUCCESS, 0)
    o = complete(vc, vc.trajectory_point(0, point(0, 0.0, far)))
    assert (o.result, o.subcode) == (R.INVALID, Inv.DATA_START_POS)
    assert "31 pulses" in o.detail
    assert "30 pulses" in o.detail


def test_start_checks_interleave_per_index() -> None:
    """Index 1's speed fails before index 2's position: 3013 wins (§3.4 step 5.3)."""
    vc = ready()
    limit = vc.motoros.axes[0].max_speed[1]
    pos = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]
    vel = [0.0, math.floor(limit) + 1.0, 0.0, 0.0, 0.0, 0.0]
    assert reply(vc, 0, point(0, 0.0, pos, vel)) == (R.INVALID, Inv.DATA_SPEED)
    vel[1] = 0.0
    pos[0] = 0.5
    assert reply(vc, 0, point(0, 0.0, pos, vel)) == (R.INVALID, Inv.DATA_START_POS)


def test_speed_check_truncates() -> None:
    vc = ready()
    limit = vc.motoros.axes[0].max_speed[0]
    assert reply(vc, 0, point(0, 0.0, [0.0] * 6)) == (R.SUCCESS, 0)
    just_below_next = math.floor(limit) + 0.99  # above the limit, but trunc() is not
    assert just_below_next > limit
    assert reply(vc, 1, point(0, 1.0, [0.1] * 6, [just_below_next] + [0.0] * 5)) == (R.SUCCESS, 0)
    tick_until(vc, lambda: not vc.motoros.interpolators[0].pending, "point taken")
    over = float(math.floor(limit) + 1)
    assert reply(vc, 2, point(0, 2.0, [0.1] * 6, [over] + [0.0] * 5)) == (R.INVALID, Inv.DATA_SPEED)


@pytest.mark.parametrize("fidelity", ["exact", "safe"])
def test_busy_and_sequence_zero_without_busy_check(fidelity: str) -> None:
    """Also docs/fidelity.md §1's race row (safe in both settings): a sequence-0 point
    while a segment is being generated abandons it and the pending point."""
    vc = ready(safe_cell() if fidelity == "safe" else None)
    assert reply(vc, 0, point(0, 0.0, [0.0] * 6)) == (R.SUCCESS, 0)
    assert reply(vc, 1, point(0, 5.0, [0.5] * 6)) == (R.SUCCESS, 0)
    assert reply(vc, 2, point(0, 6.0, [0.6] * 6)) == (R.BUSY, 0)
    assert reply(vc, 7, point(0, 6.0, [0.6] * 6)) == (R.BUSY, 0)  # no continuity check
    vc.run_ticks(5)  # the 5 s segment is being turned into increments
    assert vc.motoros.interpolators[0].pending
    # sequence 0 is never BUSY; it re-initialises the group (start check passes: not moved)
    assert reply(vc, 0, point(0, 0.0, [0.0] * 6)) == (R.SUCCESS, 0)
    assert not vc.motoros.interpolators[0].pending


def test_point_at_or_before_the_current_time_is_dropped_after_success() -> None:
    vc = ready()
    assert reply(vc, 0, point(0, 1.0, [0.0] * 6)) == (R.SUCCESS, 0)
    assert reply(vc, 1, point(0, 1.0, [0.2] * 6)) == (R.SUCCESS, 0)
    vc.run_ticks(5)
    assert not vc.has_queued_motion()
    assert vc.snapshot().groups[0].command_pulse == (0,) * 6


def two_groups() -> VirtualController:
    vc = VirtualController(cell_from_dict({"groups": [{"robot": "hc10"}, {"robot": "hc10"}]}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    return vc


def ex(vc: VirtualController, seq: int, *points: object) -> tuple[int, int, int | None]:
    from pymotoros.controller import PointData

    pts = [p for p in points if isinstance(p, PointData)]
    o = complete(vc, vc.trajectory_point_ex(seq, pts))
    return (o.result, o.subcode, o.group_no)


def test_type_2016_order_and_reply_group() -> None:
    vc = two_groups()
    z = [0.0] * 6
    assert ex(vc, 0) == (R.INVALID, Inv.DATA, -1)  # n = 0: our clear answer
    assert ex(vc, 0, point(0, 0.0, z), point(5, 0.0, z)) == (R.INVALID, Inv.GROUPNO, 5)
    assert ex(vc, 0, point(0, 0.0, z, fields=3), point(1, 0.0, z)) == (
        R.INVALID,
        Inv.DATA_INSUFFICIENT,
        0,
    )
    # no 4-hour check on 2016
    assert ex(vc, 0, point(0, 20000.0, z), point(1, 20000.0, z)) == (R.SUCCESS, 0, 1)
    assert ex(vc, 1, point(1, 20001.0, [0.1] * 6), point(0, 20001.0, [0.1] * 6)) == (
        R.SUCCESS,
        0,
        0,
    )
    # both pending → BUSY at the pre-check, on the first listed group
    assert ex(vc, 2, point(0, 20002.0, z), point(1, 20002.0, z)) == (R.BUSY, 0, 0)
    tick_until(
        vc,
        lambda: not vc.has_queued_motion() and not any(i.pending for i in vc.motoros.interpolators),
        "drained",
    )
    # a duplicated group: accepted once, BUSY the second time
    assert ex(vc, 3, point(0, 20003.0, z), point(0, 20003.0, z)) == (R.BUSY, 0, 0)
    assert ex(vc, -1, point(1, 0.0, z)) == (R.INVALID, Inv.SEQUENCE, 1)


def test_type_2016_not_ready_carries_the_last_group() -> None:
    vc = VirtualController(cell_from_dict({"groups": [{"robot": "hc10"}, {"robot": "hc10"}]}))
    z = [0.0] * 6
    assert ex(vc, 0, point(1, 0.0, z), point(0, 0.0, z))[::2] == (R.NOT_READY, 0)


def test_type_2016_start_failure_keeps_earlier_groups() -> None:
    vc = two_groups()
    o = ex(vc, 0, point(0, 0.0, [0.0] * 6), point(1, 0.0, [0.5] * 6))
    assert o == (R.INVALID, Inv.DATA_START_POS, 1)


def test_select_tool() -> None:
    vc = VirtualController()
    assert vc.select_tool(0, 63).ok
    assert vc.snapshot().groups[0].tool == 63
    assert (vc.select_tool(1, 0).result, vc.select_tool(1, 0).subcode) == (R.INVALID, Inv.GROUPNO)
    o = vc.select_tool(0, 64)
    assert (o.result, o.subcode) == (R.INVALID, Inv.DATA_TOOLNO)
    assert "64" in o.detail
    assert vc.select_tool(0, -1).subcode == Inv.DATA_TOOLNO
    assert vc.motoros.jog_tool == [63]


def test_tool_is_latched_per_segment() -> None:
    vc = ready()
    assert send(vc, 0, point(0, 0.0, [0.0] * 6)).ok
    assert send(vc, 1, point(0, 0.4, [0.05] * 6)).ok
    vc.tick()
    assert vc.select_tool(0, 5).ok
    assert {e.tool for e in vc.motoros.interpolators[0].queue} == {0}
    assert send(vc, 2, point(0, 0.8, [0.1] * 6)).ok
    tick_until(vc, lambda: not vc.motoros.interpolators[0].pending, "second segment queued")
    assert {e.tool for e in vc.motoros.interpolators[0].queue} == {0, 5}


def test_queue_count_and_bad_group() -> None:
    vc = ready()
    assert send(vc, 0, point(0, 0.0, [0.0] * 6)).ok
    assert send(vc, 1, point(0, 2.0, [0.1] * 6)).ok
    vc.tick()
    count = command(vc, CMD.CHECK_QUEUE_CNT)
    assert (count.result, count.subcode) == (R.SUCCESS, 200)
    bad = command(vc, CMD.CHECK_QUEUE_CNT, group=3)
    assert (bad.result, bad.subcode) == (R.FAILURE, -1)


def test_dh_parameters() -> None:
    vc = VirtualController()
    dh = vc.dh_parameters()
    assert dh is not None
    assert len(dh) == 4
    assert all(len(g) == 8 for g in dh)
    model = vc.cell.groups[0].dh
    assert dh[0][: len(model)] == tuple((d.theta, d.d, d.a, d.alpha) for d in model)
    assert dh[1] == ((0.0, 0.0, 0.0, 0.0),) * 8
