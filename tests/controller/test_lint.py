"""``ClientLint``: findings counted per connection, bounded, and its stateful checks
(sequence numbers, BUSY, queue starvation, reconnects) without a network."""

from __future__ import annotations

import pytest

from pymotoros.controller.lint import (
    MAX_FINDINGS,
    OTHER_CONNECTIONS,
    RULES,
    ClientLint,
    LintCode,
)
from pymotoros.protocol.constants import ResultCode

C = "10.0.0.7:51234"
OK = ResultCode.SUCCESS
BUSY = ResultCode.BUSY


def _codes(lint: ClientLint) -> list[str]:
    return [str(f.code) for f in lint.findings()]


def _stream(lint: ClientLint, sequences: list[tuple[int, int]], *, moving: bool = True) -> None:
    lint.state_clients = 1
    for t, (sequence, result) in enumerate(sequences):
        lint.point_answered(C, [(0, moving and sequence > 0)], sequence, result, t * 0.1)


def test_every_code_has_a_reference_a_text_and_a_remedy() -> None:
    assert set(RULES) == set(LintCode)
    for code, rule in RULES.items():
        assert rule.reference.startswith("§"), code
        assert rule.text.endswith("."), code
        assert rule.remedy.endswith("."), code


def test_findings_are_counted_per_code_and_connection_from_the_first_time() -> None:
    lint = ClientLint()
    lint.record(LintCode.FRAGMENTED_MESSAGE, C, 1.5, "type 2001")
    lint.record(LintCode.FRAGMENTED_MESSAGE, C, 2.0, "type 14")
    lint.record(LintCode.FRAGMENTED_MESSAGE, "10.0.0.8:1", 3.0)
    first, second = lint.findings()
    assert (first.code, first.count, first.first_s, first.connection) == (
        LintCode.FRAGMENTED_MESSAGE,
        2,
        1.5,
        C,
    )
    assert first.text.endswith("First: type 2001.")
    assert first.reference == "§1.5"
    assert first.remedy == RULES[first.code].remedy
    assert (second.count, second.connection) == (1, "10.0.0.8:1")
    assert first.as_dict()["code"] == "fragmented-message"
    lint.clear()
    assert lint.findings() == []


def test_a_fuzzer_cannot_grow_it_without_bound() -> None:
    lint = ClientLint()
    for n in range(20 * MAX_FINDINGS):
        lint.record(LintCode.UNKNOWN_COMMAND, f"10.0.0.9:{n}", n * 0.001)
        lint.record(LintCode.STALE_REPLY, f"10.0.0.9:{n}", n * 0.001)
    assert len(lint.findings()) <= MAX_FINDINGS + len(LintCode)
    other = [f for f in lint.findings() if f.connection == OTHER_CONNECTIONS]
    assert sum(f.count for f in lint.findings()) == 40 * MAX_FINDINGS
    assert other
    assert all(f.count > 1 for f in other)
    for group in range(10_000):  # points for ever-new groups: the sequence state is capped
        lint.point_answered(C, [(group, True)], 1, OK, 0.0)
    assert len(lint._sequences) <= 64


def test_consecutive_points_and_a_resent_busy_point_give_nothing() -> None:
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK), (2, BUSY), (2, BUSY), (2, OK), (3, OK), (0, OK), (1, OK)])
    assert lint.findings() == []


def test_a_gap_in_the_sequence_is_a_finding() -> None:
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK), (3, OK), (4, OK)])
    (finding,) = lint.findings()
    assert finding.code is LintCode.SEQUENCE_NOT_CONSECUTIVE
    assert "point 3 accepted where 2 was next" in finding.text


def test_advancing_after_busy_is_a_finding() -> None:
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK), (2, BUSY), (3, OK)])
    assert _codes(lint) == ["busy-point-skipped"]
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK), (2, BUSY), (3, BUSY)])
    assert _codes(lint) == ["busy-point-skipped"]


def test_a_motion_command_forgives_what_was_owed() -> None:
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK), (2, BUSY)])
    lint.motion_reset()  # STOP_MOTION: the client abandons the trajectory
    _stream(lint, [(0, OK), (1, OK)])
    assert lint.findings() == []


def test_points_without_a_state_connection_are_a_finding() -> None:
    lint = ClientLint()
    lint.point_answered(C, [(0, False)], 0, OK, 0.0)
    lint.point_answered(C, [(0, False)], 1, OK, 0.1)
    (finding,) = lint.findings()
    assert (finding.code, finding.count) == (LintCode.MOTION_WITHOUT_STATE, 2)
    lint = ClientLint()
    lint.state_clients = 1
    lint.point_answered(C, [(0, False)], 0, OK, 0.0)
    assert lint.findings() == []


def test_a_queue_that_ran_dry_after_a_moving_point_is_starved() -> None:
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK)], moving=True)
    assert lint.watching_queues
    assert lint.moving_groups() == (0,)
    lint.queue_ran_empty(0, 0.84)
    lint.queue_ran_empty(0, 0.85)  # once per starvation
    (finding,) = lint.findings()
    assert (finding.code, finding.connection, finding.first_s) == (LintCode.QUEUE_STARVED, C, 0.84)
    assert not lint.watching_queues


def test_a_trajectory_that_ends_at_rest_is_not_starved() -> None:
    lint = ClientLint()
    _stream(lint, [(0, OK), (1, OK)], moving=True)
    lint.point_answered(C, [(0, False)], 2, OK, 0.3)
    assert not lint.watching_queues
    lint.queue_ran_empty(0, 1.0)
    assert lint.findings() == []


@pytest.mark.parametrize("cleared_s", [None, 0.8], ids=["exact", "safe"])
@pytest.mark.parametrize(
    ("queued", "stops", "codes"),
    [
        (True, False, ["reconnect-resumed-motion"]),
        (True, True, []),  # STOP_MOTION first: what a client must do (docs/client.md)
        (False, False, []),
    ],
)
def test_a_motion_connection_opened_over_queued_increments(
    queued: bool, stops: bool, codes: list[str], cleared_s: float | None
) -> None:
    """The same rule in both settings; safe (``cleared_s``: the twin cleared the queues
    at the close) says that a robot would have resumed them."""
    lint = ClientLint()
    lint.motion_opened(C, 4.2, queued=queued, cleared_s=cleared_s)
    assert _codes(lint) == []  # not decided before the first request
    lint.motion_request(C, stops=stops, what="CHECK_QUEUE_CNT")
    lint.motion_request(C, stops=False, what="JOINT_TRAJ_PT_FULL")  # later: no matter
    assert _codes(lint) == codes
    assert [f.first_s for f in lint.findings()] == [4.2] * len(codes)  # when it opened
    safe_text = "safe cleared them, but a robot would have kept them and resumed them"
    for f in lint.findings():
        assert (safe_text in f.text) is (cleared_s is not None), f.text


def test_a_resumed_connection_that_sends_nothing_is_found_when_it_closes() -> None:
    lint = ClientLint()
    lint.motion_opened(C, 1.0, queued=True)
    lint.motion_closed("other:1")  # another connection: not this one
    assert lint.resume_pending
    lint.motion_closed(C)
    assert _codes(lint) == ["reconnect-resumed-motion"]
    assert "closed without sending STOP_MOTION" in lint.findings()[0].text
    lint.motion_closed(C)  # already reported: not twice
    assert lint.findings()[0].count == 1


def test_the_simulator_guide_lists_every_code_with_its_reference() -> None:
    from pathlib import Path

    guide = (Path(__file__).resolve().parents[2] / "docs" / "sim.md").read_text()
    for code, rule in RULES.items():
        assert f"| `{code}` | {rule.reference} |" in guide, code
