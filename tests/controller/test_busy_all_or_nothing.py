"""JOINT_TRAJ_PT_FULL_EX (2016) and BUSY: all or nothing (reference §3.5 step 2).

MotoROS pre-checks every listed group, in message order, before it applies any: a
pending group answers BUSY and *no* group of the message is accepted. Without that
pre-check the controller would accept the free groups, then answer BUSY on the pending
one, and the client's resend would queue the free groups' point a second time.

Every combination of pending groups is tried for 2, 3 and 4 groups, with the groups
listed in order and reversed; the expected reply and state are written from the
reference, not read from the controller.
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Iterator, Sequence
from functools import partial

import pytest

from pymotoros.controller import PointData, VirtualController, cell_from_dict
from pymotoros.motion.interpolator import GroupInterpolator
from pymotoros.protocol.constants import ResultCode as R

from .helpers import CMD, command, complete, point, resend_while_busy

ZERO = [0.0] * 6
FAR_S = 5.0
"""A pending point this far ahead stays pending for thousands of ticks (the queue holds
0.8 s), so "pending" is a state the test sets, not a race."""


def started(n: int) -> VirtualController:
    """``n`` HC10 groups in trajectory mode, each started at 0 (sequence 0) and idle."""
    vc = VirtualController(cell_from_dict({"groups": [{"robot": "hc10"}] * n}))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    o = complete(vc, vc.trajectory_point_ex(0, [point(g, 0.0, ZERO) for g in range(n)]))
    assert (o.result, o.subcode) == (R.SUCCESS, 0), o
    return vc


def make_pending(vc: VirtualController, groups: Sequence[int]) -> None:
    for g in groups:
        o = complete(vc, vc.trajectory_point(1, point(g, FAR_S, [0.2] * 6)))
        assert (o.result, o.subcode) == (R.SUCCESS, 0), o
        assert vc.motoros.interpolators[g].pending


def pending(vc: VirtualController) -> tuple[bool, ...]:
    return tuple(i.pending for i in vc.motoros.interpolators)


def cases() -> Iterator[tuple[int, tuple[int, ...], tuple[int, ...]]]:
    """(groups, pending groups, listed order) for every subset and both orders."""
    for n in (2, 3, 4):
        for k in range(n + 1):
            for busy in itertools.combinations(range(n), k):
                yield n, busy, tuple(range(n))
                yield n, busy, tuple(reversed(range(n)))


@pytest.mark.parametrize(
    ("n", "busy", "order"),
    [
        pytest.param(n, b, o, id=f"{n}groups-pending{list(b)}-{'up' if o[0] == 0 else 'down'}")
        for n, b, o in cases()
    ],
)
def test_one_pending_group_refuses_the_whole_message(
    n: int, busy: tuple[int, ...], order: tuple[int, ...]
) -> None:
    vc = started(n)
    make_pending(vc, busy)
    before = pending(vc)
    assert before == tuple(g in busy for g in range(n))
    msg = [point(g, 1.0, [0.1] * 6) for g in order]
    o = complete(vc, vc.trajectory_point_ex(2, msg))
    if busy:
        first_pending = next(g for g in order if g in busy)
        # BUSY names the first pending group in message order ...
        assert (o.result, o.subcode, o.group_no) == (R.BUSY, 0, first_pending)
        # ... and no group of the message was accepted: the free ones are still free
        assert pending(vc) == before
    else:
        # all free: every group accepted, the reply carries the last listed group
        assert (o.result, o.subcode, o.group_no) == (R.SUCCESS, 0, order[-1])
        assert pending(vc) == (True,) * n


def test_a_busy_reply_leaves_the_free_groups_untouched_until_they_move() -> None:
    """After BUSY the free group's motion is what it was: it never moves toward the
    refused point (nothing of the message was queued for it)."""
    vc = started(2)
    make_pending(vc, [1])
    o = complete(vc, vc.trajectory_point_ex(2, [point(0, 1.0, [0.1] * 6), point(1, 1.0, ZERO)]))
    assert o.result == R.BUSY
    vc.run_ticks(300)  # 1.2 s: the refused point's time has passed
    assert vc.snapshot().groups[0].command_pulse == (0,) * 6
    assert not vc.motoros.interpolators[0].pending


@pytest.fixture
def accepted(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    """How many points each group accepted (sequence > 0), by group name."""
    counts: Counter[str] = Counter()
    original = GroupInterpolator.set_pending_point

    def counting(self: GroupInterpolator, p: object) -> None:
        original(self, p)  # type: ignore[arg-type]
        counts[self.axes.name] += 1

    monkeypatch.setattr(GroupInterpolator, "set_pending_point", counting)
    return counts


def resend_until_accepted(vc: VirtualController, sequence: int, pts: list[PointData]) -> int:
    """What every client does (reference §2: BUSY makes it resend the same point):
    resend after a tick until the reply is not BUSY. Returns the BUSY replies seen."""
    o, busy = resend_while_busy(vc, partial(vc.trajectory_point_ex, sequence, pts), 5000)
    if o.result == R.BUSY:
        raise AssertionError("still BUSY after 5000 ticks")
    assert o.ok, o
    return busy


@pytest.mark.parametrize("n", [2, 3, 4])
def test_the_resend_queues_each_point_exactly_once(n: int, accepted: Counter[str]) -> None:
    vc = started(n)
    names = [i.axes.name for i in vc.motoros.interpolators]
    make_pending(vc, [n - 1])  # the last group is busy, the others free
    assert accepted == Counter({names[n - 1]: 1})
    busy = resend_until_accepted(vc, 2, [point(g, FAR_S + 1.0, [0.3] * 6) for g in range(n)])
    assert busy > 0  # the case under test happened
    assert accepted == Counter({name: 1 for name in names[:-1]} | {names[n - 1]: 2})


async def test_the_clients_resend_queues_each_point_once(accepted: Counter[str]) -> None:
    """The same through the real client's BUSY retry (``TrajectoryStreamer.send_point``),
    over the in-memory twin: group 1 pending, group 0 free."""
    from pymotoros.client import StreamStats
    from pymotoros.client.planning import TrajectoryPoint
    from pymotoros.client.streaming import build_message
    from pymotoros.testing import twin

    cell = cell_from_dict({"groups": [{"robot": "hc10"}, {"robot": "hc10"}]})
    async with twin(cell=cell, timeout_s=5.0) as (client, the_twin):
        await client.enable()
        start = TrajectoryPoint(0.0, tuple(ZERO * 2), tuple(ZERO * 2))
        streamer = client.streamer
        stats = StreamStats()
        reply = await streamer.send_point(
            build_message(start, 0, [0, 1], [6, 6]), busy_timeout_s=10.0, stats=stats
        )
        assert reply.result == R.SUCCESS
        one = TrajectoryPoint(FAR_S, tuple([0.2] * 6), tuple(ZERO))
        reply = await streamer.send_point(
            build_message(one, 1, [1], [6]), busy_timeout_s=10.0, stats=stats
        )
        assert reply.result == R.SUCCESS
        names = [i.axes.name for i in the_twin.controller.motoros.interpolators]
        assert accepted == Counter({names[1]: 1})
        both = TrajectoryPoint(FAR_S + 1.0, tuple([0.3] * 12), tuple(ZERO * 2))
        reply = await streamer.send_point(
            build_message(both, 2, [0, 1], [6, 6]), busy_timeout_s=10.0, stats=stats
        )
        assert reply.result == R.SUCCESS
        assert stats.busy_replies > 0
        assert accepted == Counter({names[0]: 1, names[1]: 2})
