"""``pymotoros sim --realtime`` in a real process: real-time policy, or one warning line."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import httpx
import pytest

from pymotoros.runtime.realtime import REALTIME_PRIORITY

from .test_sim import running


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux scheduling policies")
def test_realtime_is_applied_or_refused_in_one_warning_line(tmp_path: Path) -> None:
    with running(tmp_path, "--realtime", "--no-idle-batching") as sim:
        policy = os.sched_getscheduler(sim.proc.pid)
        priority = os.sched_getparam(sim.proc.pid).sched_priority
        reply = httpx.get(f"{sim.api}/api/state", timeout=10.0)
        assert reply.status_code == 200
        log = sim.stderr.read_text()
    if policy == os.SCHED_FIFO:  # root, CAP_SYS_NICE or ulimit -r
        assert priority == REALTIME_PRIORITY
        assert "--realtime not applied" not in log
    else:  # not permitted: said once, and the twin runs on normal scheduling
        assert policy == os.SCHED_OTHER
        assert log.count("--realtime not applied") == 1
