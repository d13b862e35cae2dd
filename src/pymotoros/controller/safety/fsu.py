"""The Functional Safety Unit's speed limits, switchable at run time.

The FSU is the controller's, not MotoROS's: it clips each tick's increment to what the
active limits allow and drops the rest, with no signal to anyone (seed 003, Appendix B).
MotoROS 1.9.12 notices only through the incremental-move results (the commanded
position moved less than it sent) and resends the missing pulses (reference §5.6 step 3).

:meth:`FsuFunction.limits` is the one place the per-tick, per-axis clip is computed; it
combines the joint-speed limit (a share of each axis's maximum increment) with any
TCP-speed clip. The TCP-speed limit needs forward kinematics: the controller gives its
kinematics as the ``tcp_limiter`` port when it builds the unit (an
:data:`IncrementLimiter`, which sees each tick's intended increment and scales it so
that the TCP moves no faster than the limit, :meth:`FsuFunction.tcp_clip`); an FSU
built without one refuses a TCP-speed request with a message saying so.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from typing import TypedDict

from pymotoros.controller.servo import ServoGroup
from pymotoros.controller.values import FsuLimits
from pymotoros.models.fsu import fsu_joint_clip
from pymotoros.motion import GroupAxes

logger = logging.getLogger(__name__)

IncrementLimiter = Callable[[float, int, Sequence[int], Sequence[int]], Sequence[int]]
"""The TCP-speed port: ``(tcp_speed_mm_s, group index, commanded pulses, intended
increment) -> per-slot maximum |increment| (pulses) for this tick``. The controller
gives it from its kinematics (``controller.tool_point.TcpTracker``) at construction."""


class FsuRequest(TypedDict, total=False):
    """The keyword arguments of a run-time FSU switch (:meth:`FsuFunction.set`), declared
    once so that the controller's protocol and its facade pass them on without a copy."""

    joint_speed_pct: int | None
    """Each axis at most this share (1..100 %) of its maximum speed; None: unchanged."""
    tcp_speed_mm_s: float | None
    """The TCP at most this fast (> 0 mm/s); None: unchanged."""
    off: bool
    """Clear every limit (not together with a limit)."""


TCP_NEEDS_KINEMATICS = (
    "the FSU TCP-speed limit (tcp_speed_mm_s) needs the robot's kinematics model, which "
    "this build of the virtual controller does not have yet; use joint_speed_pct"
)


class FsuFunction:
    """The FSU's joint-speed (and, once kinematics exist, TCP-speed) limit."""

    def __init__(
        self,
        axes: Sequence[GroupAxes],
        servos: Sequence[ServoGroup],
        boot_joint_speed_pct: int | None,
        *,
        tcp_limiter: IncrementLimiter | None = None,
    ) -> None:
        """``tcp_limiter``: the kinematics that clip a tick's increment to a TCP speed
        (None: no kinematics, a TCP-speed limit is refused)."""
        self._axes = tuple(axes)
        self._servos = tuple(servos)
        self._tcp_limiter = tcp_limiter
        self._joint_pct: int | None = None
        self._tcp: float | None = None
        self._joint_clip: tuple[tuple[int, ...], ...] | None = None
        self._set_joint(boot_joint_speed_pct)
        self.switches = 0
        """Limit switches at run time since boot (``GET /metrics``)."""

    @property
    def active(self) -> FsuLimits:
        return FsuLimits(self._joint_pct, self._tcp)

    def set(
        self,
        *,
        joint_speed_pct: int | None = None,
        tcp_speed_mm_s: float | None = None,
        off: bool = False,
    ) -> None:
        """Switch limits at run time: each given limit replaces that limit; ``off`` clears all.

        Raises ValueError for a value out of range, ``off`` with a limit, nothing given,
        or a TCP-speed limit without kinematics (no ``tcp_limiter``).
        """
        if off:
            if joint_speed_pct is not None or tcp_speed_mm_s is not None:
                raise ValueError("FSU: give either off=true or limits, not both")
            logger.info("FSU limits off")
            self._set_joint(None)
            self._tcp = None
            self.switches += 1
            return
        if joint_speed_pct is None and tcp_speed_mm_s is None:
            raise ValueError("FSU: give joint_speed_pct, tcp_speed_mm_s or off=true")
        if joint_speed_pct is not None and not 1 <= joint_speed_pct <= 100:
            raise ValueError(f"FSU: joint_speed_pct must be 1..100, not {joint_speed_pct}")
        if tcp_speed_mm_s is not None:
            if not tcp_speed_mm_s > 0:
                raise ValueError(f"FSU: tcp_speed_mm_s must be > 0, not {tcp_speed_mm_s}")
            if self._tcp_limiter is None:
                raise ValueError(TCP_NEEDS_KINEMATICS)
        if joint_speed_pct is not None:
            logger.info("FSU joint-speed limit %d %%", joint_speed_pct)
            self._set_joint(joint_speed_pct)
        if tcp_speed_mm_s is not None:
            logger.info("FSU TCP-speed limit %g mm/s", tcp_speed_mm_s)
            self._tcp = float(tcp_speed_mm_s)
        self.switches += 1

    def _set_joint(self, pct: int | None) -> None:
        self._joint_pct = pct
        self._joint_clip = (
            None if pct is None else tuple(fsu_joint_clip(a.max_increment, pct) for a in self._axes)
        )

    def limits(self) -> tuple[tuple[int, ...], ...] | None:
        """Per group and slot, the most pulses the joint-speed limit lets the controller
        execute this tick; None when no limit is on. With only the TCP-speed limit on it
        is each axis's maximum increment: the TCP clip itself depends on the increment
        (:meth:`tcp_clip`)."""
        if self._joint_clip is not None:
            return self._joint_clip
        if self._tcp is not None and self._tcp_limiter is not None:
            return tuple(a.max_increment for a in self._axes)
        return None

    def tcp_clip(
        self, group: int, command: Sequence[int], increment: Sequence[int]
    ) -> Sequence[int] | None:
        """Per slot, the most pulses the TCP-speed limit lets ``increment`` execute from
        ``command`` this tick; None when that limit is off."""
        tcp = self._tcp
        limiter = self._tcp_limiter
        if tcp is None or limiter is None:
            return None
        return limiter(tcp, group, command, increment)
