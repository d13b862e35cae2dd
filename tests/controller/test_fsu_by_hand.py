"""FSU clips tick by tick, against numbers worked out by hand from the reference.

The FSU executes at most its clip per axis and tick and drops the rest; MotoROS resends
what is missing, clamped to what was executed the tick before (reference §5.6 step 3).
So while a move asks for more than the clip, the commanded position advances by exactly
the clip on most ticks, never more; the odd shorter tick is the one on which MotoROS
reads the queue again after a resend. The expected clips are written here, computed by hand:

* joint limit 5 % on the HC10's S axis: maxInc 741 (81646.4858 pulses/rad × 130°/s ×
  4 ms, §5.5), 741 × 5 // 100 = 37 pulses a tick (10 % would give 74);
* TCP limit 100 mm/s, S axis only, from the zero pose: the flange (tool 0) sits 0.162 m
  from the S axis (the B-axis offset of robot-models.md §1.2; every other offset of the
  HC10 chain is along the S axis), so one S pulse moves it 0.162 m / 81646.4858 =
  1.98417 µm; 100 mm/s × 4 ms = 0.4 mm a tick, 0.4 mm / 1.98417 µm = 201.6 → 201 pulses
  (the clip rounds down so the TCP never exceeds the limit).
"""

from __future__ import annotations

from pymotoros.controller import VirtualController, cell_from_dict

from .helpers import CMD, command, point, send, start_at_current

JOINT_5_PCT_S_CLIP = 37
TCP_100_MM_S_S_CLIP = 201


def _s_axis_steps(joint_pct: int | None, tcp_mm_s: float | None, ticks: int) -> list[int]:
    """Per tick, the S axis's commanded pulse change during a fast S-only move."""
    vc = VirtualController(cell_from_dict({"controller": {"pfl": False}}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert start_at_current(vc).ok
    vc.set_fsu(joint_speed_pct=joint_pct, tcp_speed_mm_s=tcp_mm_s)
    # 1 rad in 0.6 s: up to ~2 rad/s, several hundred pulses a tick unclipped
    assert send(vc, 1, point(0, 0.6, [1.0, 0, 0, 0, 0, 0])).ok
    steps = []
    before = vc.snapshot().groups[0].command_pulse[0]
    for _ in range(ticks):
        vc.tick()
        now = vc.snapshot().groups[0].command_pulse[0]
        steps.append(now - before)
        before = now
    return steps


def test_joint_limit_5_pct_executes_37_pulses_a_tick() -> None:
    steps = _s_axis_steps(5, None, 400)
    assert max(steps) == JOINT_5_PCT_S_CLIP
    # once the move asks for more than the clip it runs at the clip on most ticks
    assert steps[100:400].count(JOINT_5_PCT_S_CLIP) > 0.85 * 300


def test_tcp_limit_100_mm_s_executes_201_pulses_a_tick() -> None:
    steps = _s_axis_steps(None, 100.0, 200)
    assert max(steps) == TCP_100_MM_S_S_CLIP
    assert steps[100:200].count(TCP_100_MM_S_S_CLIP) > 0.7 * 100
