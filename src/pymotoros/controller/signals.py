"""Controller signal addresses MotoROS reads or writes, as named constants.

Bit addresses follow the Yaskawa IO map: the last decimal digit is the bit (0..7)
of the byte numbered by the other digits. Sources are sections of
``shared/reference/motoros-1.9.12.md``.
"""

from __future__ import annotations

from typing import Final

# --- specific outputs read by the 10 ms status monitor (§2.6)
ALARM_MAJOR: Final = 50010
ALARM_MINOR: Final = 50011
ALARM_SYSTEM: Final = 50012
ALARM_USER: Final = 50013
ALARM_BITS: Final = (ALARM_MAJOR, ALARM_MINOR, ALARM_SYSTEM, ALARM_USER)
ERROR: Final = 50014
"""Operator error (not an alarm: it does not set ``in_error``)."""
TEACH: Final = 50053
PLAY: Final = 50054
OPERATING: Final = 50070
"""A job is being played back (the INIT_ROS job waiting at its WAIT counts)."""
HOLD: Final = 50071
SERVO_ON: Final = 50073
ECO_MODE: Final = 50727
"""Energy-saving mode: servo power is off although 50073 may still read on (§2.6)."""

# --- control status (§2.6); the E-stop inputs read 1 while *not* stopped
REMOTE: Final = 80011
"""Remote mode (50056 before July 2013)."""
ESTOP_EXTERNAL: Final = 80025
ESTOP_PENDANT: Final = 80026
ESTOP_CONTROLLER: Final = 80027
ESTOP_BITS: Final = (ESTOP_EXTERNAL, ESTOP_PENDANT, ESTOP_CONTROLLER)

# --- PFL (power and force limiting), YRC1000 / YRC1000micro builds only (§2.6, §4.1)
PFL_STOP: Final = 81702
PFL_ESCAPE: Final = 81703
PFL_AVOIDING: Final = 15120
PFL_AVOID_JOINT: Final = 15124
PFL_AVOID_TRANSLATION: Final = 15125
PFL_BITS: Final = (PFL_STOP, PFL_ESCAPE, PFL_AVOIDING, PFL_AVOID_JOINT, PFL_AVOID_TRANSLATION)


def universal_output(n: int) -> int:
    """Bit address of universal output OT#n (§6.3): 10010 + 10·⌊(n−1)/8⌋ + (n−1) mod 8."""
    if n < 1:
        raise ValueError(f"universal outputs are numbered from 1, got OT#{n}")
    return 10010 + 10 * ((n - 1) // 8) + (n - 1) % 8


# --- MotoROS feedback outputs OT#889..896 (§6.3)
ROS_READY: Final = 11120
"""OT#889, set by the INIT_ROS job when it reaches its WAIT; MotoROS only reads it."""
ROS_DONE: Final = 11121
"""OT#890, set by MotoROS on STOP_TRAJ_MODE / DISCONNECT to release the job."""
INIT_DONE: Final = 11122
"""OT#891, MotoROS initialised."""
CONNECT_SERVER_RUNNING: Final = 11123
"""OT#892, connection server task running."""
MOTION_SERVER_CONNECTED: Final = 11124
"""OT#893, a motion connection exists."""
STATE_SERVER_CONNECTED: Final = 11125
"""OT#894, at least one state connection exists."""
IO_SERVER_CONNECTED: Final = 11126
"""OT#895, an IO connection was set up (never cleared)."""
FAILURE: Final = 11127
"""OT#896, initialisation or task-creation failure."""
FEEDBACK_OUTPUTS: Final = tuple(range(11120, 11128))
RESERVED_OUTPUTS: Final = tuple(range(11130, 11138))
"""OT#897..904, cleared at start-up only."""

MONITORED: Final = frozenset(
    {
        *ALARM_BITS,
        ERROR,
        TEACH,
        PLAY,
        REMOTE,
        OPERATING,
        HOLD,
        SERVO_ON,
        *ESTOP_BITS,
        ROS_READY,
        ECO_MODE,
        *PFL_BITS,
    }
)
"""Every address the status monitor reads in its one multi-address read (§2.6)."""
