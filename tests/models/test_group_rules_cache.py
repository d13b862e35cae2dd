"""group_rules remembers by identity first, and equal models still give equal rules."""

from __future__ import annotations

import copy

from pymotoros.models import ROBOTS, controller_model, robot_model
from pymotoros.models.rules import RECENT_RULES, GroupRules, group_rules


def test_the_same_models_give_the_same_rules_object_and_equal_copies_equal_rules() -> None:
    controller = controller_model("YRC1000")
    group = robot_model("hc10").groups[0]
    first = group_rules(group, controller)
    assert group_rules(group, controller) is first
    twin_group, twin_controller = copy.deepcopy(group), copy.deepcopy(controller)
    assert twin_group is not group
    assert group_rules(twin_group, twin_controller) == first
    assert repr(first) == repr(GroupRules.from_model(group, controller))  # NaN slots: by repr


def test_more_pairs_than_remembered_still_give_each_its_own_rules() -> None:
    pairs = [
        (robot_model(name).groups[0], controller_model(ctrl))
        for name in sorted(ROBOTS)
        for ctrl in ("YRC1000", "DX200")
    ]
    assert len(pairs) > RECENT_RULES
    for _ in range(2):
        for group, controller in pairs:
            got = group_rules(group, controller)
            assert repr(got) == repr(GroupRules.from_model(group, controller))
