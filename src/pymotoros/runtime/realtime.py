"""Opt-in real-time scheduling for a simulator process (``pymotoros sim --realtime``).

On a loaded machine (16 twins on 2 cores) the interpolation loop is late mostly because
the scheduler runs someone else when its timer fires. Linux's real-time policies put a
process ahead of every normal (SCHED_OTHER) process the moment it becomes runnable:
SCHED_FIFO at a low priority makes a twin's wake-up preempt compilers and test runners
while twins still take turns among themselves. A twin spends most of each period
asleep, so it cannot starve the machine; the kernel's real-time throttling
(``/proc/sys/kernel/sched_rt_runtime_us``, 95 % by default) is the safety net anyway.

It needs CAP_SYS_NICE or an ``RLIMIT_RTPRIO`` above 0 (``ulimit -r``, or
``LimitRTPRIO=`` in a systemd unit, ``--cap-add SYS_NICE`` for a container); without
them, or off Linux, :func:`request_realtime` says so in one warning line and the
process runs on as before: never silently.
"""

from __future__ import annotations

import logging
import os
import sys
from typing import Final

__all__ = ["REALTIME_PRIORITY", "request_realtime"]

logger = logging.getLogger(__name__)

REALTIME_PRIORITY: Final = 10
"""SCHED_FIFO priority (1..99): low, below the kernel's own real-time threads (50 for
threaded IRQs) so that a twin never delays interrupt handling, above every normal
process."""


def request_realtime(priority: int = REALTIME_PRIORITY) -> str | None:
    """Ask for SCHED_FIFO at ``priority`` for this process (all its threads started
    afterwards inherit it). Returns None on success, else the reason (also logged as
    one warning line)."""
    reason = _try_fifo(priority)
    if reason is None:
        logger.info("real-time scheduling: SCHED_FIFO priority %d", priority)
    else:
        logger.warning("--realtime not applied: %s; running with normal scheduling", reason)
    return reason


def _try_fifo(priority: int) -> str | None:
    if not sys.platform.startswith("linux") or not hasattr(os, "sched_setscheduler"):
        return f"real-time scheduling is only supported on Linux (this is {sys.platform})"
    low = os.sched_get_priority_min(os.SCHED_FIFO)
    high = os.sched_get_priority_max(os.SCHED_FIFO)
    if not low <= priority <= high:
        return f"SCHED_FIFO priority must be in {low}..{high}, got {priority}"
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except PermissionError:
        return (
            "not permitted (EPERM): needs CAP_SYS_NICE or an RLIMIT_RTPRIO of at least "
            f"{priority} (ulimit -r; docker run --cap-add SYS_NICE)"
        )
    except OSError as exc:
        return f"sched_setscheduler failed: {exc}"
    return None
