"""Named poses from SRDF files and the built-in home."""

from __future__ import annotations

from pathlib import Path

import pytest

from pymotoros.client.srdf import NamedPoseError, builtin_home, find_pose, parse_srdf
from pymotoros.models import robot_model

HC10 = robot_model("hc10").groups[0]
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "hc10.srdf"

SRDF = """<?xml version="1.0"?>
<robot name="motoman_hc10">
  <group name="manipulator"><chain base_link="base_link" tip_link="tool0"/></group>
  <group_state name="ready" group="manipulator">
    <joint name="joint_1_s" value="0"/><joint name="joint_2_l" value="0.2"/>
    <joint name="joint_3_u" value="0.3"/><joint name="joint_4_r" value="0"/>
    <joint name="joint_5_b" value="-1.57"/><joint name="joint_6_t" value="0"/>
  </group_state>
  <group_state name="partial" group="manipulator">
    <joint name="joint_1_s" value="1"/>
  </group_state>
</robot>
"""


def test_parse_keeps_order_and_values() -> None:
    poses = parse_srdf(SRDF)
    assert [p.name for p in poses] == ["ready", "partial"]
    assert poses[0].positions_for(HC10) == (0.0, 0.2, 0.3, 0.0, -1.57, 0.0)


def test_missing_joint_is_named() -> None:
    pose = find_pose("partial", HC10, parse_srdf(SRDF))
    with pytest.raises(NamedPoseError, match="joint_2_l"):
        pose.positions_for(HC10)


def test_home_is_built_in_and_unknown_lists_known() -> None:
    assert find_pose("home", HC10).positions_for(HC10) == HC10.home
    assert builtin_home(HC10).group == "R1"
    with pytest.raises(NamedPoseError, match="home, partial, ready"):
        find_pose("nowhere", HC10, parse_srdf(SRDF))


def test_bad_files_are_clear(tmp_path: Path) -> None:
    with pytest.raises(NamedPoseError, match="cannot read"):
        parse_srdf(tmp_path / "missing.srdf")
    bad = tmp_path / "bad.srdf"
    bad.write_text("<robot><group_state name='x'><joint name='a' value='q'/></group_state></robot>")
    with pytest.raises(NamedPoseError, match="not a number"):
        parse_srdf(bad)


def test_shipped_example_srdf_fits_the_hc10() -> None:
    poses = parse_srdf(EXAMPLE)
    assert len(poses) >= 3
    for pose in poses:
        values = pose.positions_for(HC10)
        for axis, v in zip(HC10.axes, values, strict=True):
            assert axis.lower <= v <= axis.upper
