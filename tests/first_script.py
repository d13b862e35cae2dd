"""What a user's first blocking script does, shared by the tests that run one against a
simulator or the ``pymotoros_twin`` fixture."""

from __future__ import annotations

from pymotoros.client import SyncRobotClient

TOLERANCE = 1e-3
"""Radians: where a finished move must end (a pulse is ~1e-5 rad; the stop is exact)."""


def move_b_and_set_an_output(robot: SyncRobotClient, b_rad: float) -> None:
    """Wait for the state, enable, move the B axis to ``b_rad`` (every other joint at 0)
    and check it ended there; then write output 10020 and read it back."""
    robot.wait_for_state()
    robot.enable()
    result = robot.move_joints([0.0, 0.0, 0.0, 0.0, b_rad, 0.0])
    assert abs(result.final_positions[4] - b_rad) < TOLERANCE
    robot.write_io_bit(10020, 1)
    assert robot.read_io_bit(10020) == 1
