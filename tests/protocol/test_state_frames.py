"""The state server's one-pack frames are the bytes the message classes encode."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from pymotoros.protocol.constants import ByteOrder
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import JointFeedback, RobotStatus
from pymotoros.protocol.state_frames import joint_feedback_frame, robot_status_frame

# Values as the controller produces them: float32 numbers (finite), ints in int32.
float32s = st.floats(width=32, allow_nan=False, allow_infinity=False)
joints = st.lists(float32s, min_size=10, max_size=10).map(tuple)
int32s = st.integers(-(2**31), 2**31 - 1)


@given(st.sampled_from(list(ByteOrder)), st.integers(0, 3), st.integers(0, 15), joints, joints)
def test_joint_feedback_frame_is_the_encoded_message(
    order: ByteOrder, group: int, fields: int, pos: tuple[float, ...], vel: tuple[float, ...]
) -> None:
    expected = encode(JointFeedback(group, fields, 0.0, pos, vel), order)
    assert joint_feedback_frame(order, group, fields, pos, vel) == expected


@given(st.sampled_from(list(ByteOrder)), st.lists(int32s, min_size=7, max_size=7))
def test_robot_status_frame_is_the_encoded_message(order: ByteOrder, fields: list[int]) -> None:
    assert robot_status_frame(order, fields) == encode(RobotStatus(*fields), order)


def test_a_float32_from_numpy_packs_the_same() -> None:
    """The state view hands over numpy's float32 results as Python floats."""
    pos = tuple(np.float32(x).item() for x in np.linspace(-3.1, 3.1, 10))
    order = ByteOrder.LITTLE
    assert joint_feedback_frame(order, 0, 6, pos, pos) == encode(
        JointFeedback(0, 6, 0.0, pos, pos), order
    )
