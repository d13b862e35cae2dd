"""``--realtime``: SCHED_FIFO when permitted, one clear warning line when not (issue 13)."""

from __future__ import annotations

import logging
import os
import sys

import pytest

from pymotoros.runtime import realtime
from pymotoros.runtime.realtime import REALTIME_PRIORITY, request_realtime


def _refuse(pid: int, policy: int, param: object) -> None:
    raise PermissionError(1, "Operation not permitted")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux scheduling policies")
def test_eperm_is_one_warning_line_and_the_process_runs_on(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(os, "sched_setscheduler", _refuse)
    with caplog.at_level(logging.WARNING, logger=realtime.__name__):
        reason = request_realtime()
    assert reason is not None
    assert "EPERM" in reason
    assert "CAP_SYS_NICE" in reason
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    message = warnings[0].getMessage()
    assert "\n" not in message
    assert message.startswith("--realtime not applied: not permitted (EPERM)")


def test_not_linux_is_refused_with_a_warning(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(sys, "platform", "darwin")
    with caplog.at_level(logging.WARNING, logger=realtime.__name__):
        reason = request_realtime()
    assert reason == "real-time scheduling is only supported on Linux (this is darwin)"
    assert [r.getMessage() for r in caplog.records] == [
        f"--realtime not applied: {reason}; running with normal scheduling"
    ]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux scheduling policies")
def test_a_priority_out_of_range_is_refused(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger=realtime.__name__):
        reason = request_realtime(1000)
    assert reason is not None
    assert "got 1000" in reason
    assert os.sched_getscheduler(0) != os.SCHED_FIFO


def test_the_default_priority_is_low() -> None:
    if sys.platform.startswith("linux"):
        assert os.sched_get_priority_min(os.SCHED_FIFO) <= REALTIME_PRIORITY
    assert REALTIME_PRIORITY < 50  # below the kernel's threaded interrupt handlers
