"""The FSU joint clip's numbers, worked out by hand (not read back from the code).

HC10 on a YRC1000 (4 ms): maxInc = trunc(pulses/rad × rad/s × 0.004) (reference §5.5):
S, L 81646.4858 × 2.2689280 (130°/s) × 0.004 = 741.0 → 741; U 71619.7244 × π × 0.004 =
900.0 → 900; R 52998.596 × π × 0.004 = 666.0 → 666; B 52139.159 × 4.3633231 × 0.004 =
910.0 → 910; T 37242.257 × 4.3633231 × 0.004 = 650.0 → 650. A limit of p % lets each
axis do ``max(1, maxInc × p // 100)`` pulses a tick, 0 for an empty slot.
"""

from __future__ import annotations

import pytest

from pymotoros.controller import VirtualController
from pymotoros.models.fsu import fsu_joint_clip
from pymotoros.trajectory.check import fsu_clip

HC10_MAX_INC = (741, 741, 900, 666, 910, 650, 0, 0)

# pct → per slot, by hand: 741·5/100 = 37.05, 900·5/100 = 45, 666·5/100 = 33.3, ...
BY_HAND = {
    1: (7, 7, 9, 6, 9, 6, 0, 0),
    5: (37, 37, 45, 33, 45, 32, 0, 0),
    10: (74, 74, 90, 66, 91, 65, 0, 0),
    25: (185, 185, 225, 166, 227, 162, 0, 0),
    50: (370, 370, 450, 333, 455, 325, 0, 0),
    100: (741, 741, 900, 666, 910, 650, 0, 0),
}


def test_the_hc10_maximum_increments_are_the_hand_computed_ones() -> None:
    assert VirtualController().motoros.axes[0].max_increment == HC10_MAX_INC


@pytest.mark.parametrize("pct", sorted(BY_HAND))
def test_joint_clip_by_hand(pct: int) -> None:
    assert fsu_joint_clip(HC10_MAX_INC, pct) == BY_HAND[pct]


def test_at_least_one_pulse_and_nothing_for_an_empty_slot() -> None:
    # 50·1/100 = 0.5 → 0, raised to the one-pulse floor; maxInc 0 stays 0
    assert fsu_joint_clip((50, 99, 100, 0), 1) == (1, 1, 1, 0)


@pytest.mark.parametrize("pct", sorted(BY_HAND))
def test_the_twin_and_the_offline_check_use_these_numbers(pct: int) -> None:
    vc = VirtualController()
    vc.set_fsu(joint_speed_pct=pct)
    limits = vc.safety.fsu.limits()
    assert limits is not None
    assert limits[0] == BY_HAND[pct]
    assert fsu_clip(vc.motoros.axes[0], pct) == BY_HAND[pct]
