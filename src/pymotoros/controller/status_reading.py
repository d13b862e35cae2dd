"""One read of the signals MotoROS's 10 ms status monitor watches (reference §2.6).

A value object shared by the monitor that takes it, the flags computed from it and the
NOT_READY reasons that explain it; what a reading *means* (E-stopped, in error, a PFL
signal active) is said here once.
"""

from __future__ import annotations

from typing import Final, NamedTuple

STATUS_PERIOD_MS: Final = 10
"""The status monitor reads the signals every 10 ms (§2.1 step 6, §5.1)."""


class StatusReading(NamedTuple):
    """One read of every signal the status monitor watches (§2.6), as 0/1 values."""

    alarm_bits: tuple[int, ...]
    """Major, minor, system, user alarm outputs (50010..50013)."""
    error: int
    play: int
    teach: int
    remote: int
    operating: int
    hold: int
    servo: int
    estop_ok: tuple[int, ...]
    """The three E-stop inputs; 1 = not pressed."""
    ros_ready: int
    """OT#889 (11120)."""
    eco: int
    pfl: tuple[int, ...]
    """PFL stop, escape, avoiding, avoid joint, avoid translation (0 without PFL signals)."""

    @property
    def estopped(self) -> bool:
        return not all(self.estop_ok)

    @property
    def in_error(self) -> bool:
        """An alarm output is on (an operator error is not an alarm)."""
        return any(self.alarm_bits)

    @property
    def pfl_active(self) -> bool:
        """A PFL signal says the robot is stopped or avoiding (§4.1)."""
        return pfl_signals_active(self.pfl)


BOOT_READING: Final = StatusReading(
    (0, 0, 0, 0), 0, 0, 0, 0, 0, 0, 0, (1, 1, 1), 0, 0, (0, 0, 0, 0, 0)
)
"""What the monitor is taken to have read before its first run."""


def pfl_signals_active(pfl: tuple[int, ...]) -> bool:
    stop, escape, avoiding, avoid_joint, avoid_translation = pfl
    return bool(stop or escape or (avoiding and (avoid_joint or avoid_translation)))
