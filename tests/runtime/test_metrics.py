"""``GET /metrics`` scraped while the twin serves: counters rise with traffic (issue 23)."""

from __future__ import annotations

from collections.abc import AsyncIterator
from dataclasses import replace

import httpx
import pytest
from prometheus_client.parser import text_string_to_metric_families

from pymotoros.controller import VirtualController
from pymotoros.protocol.constants import MotionCommand, MsgType, Port, ResultCode
from pymotoros.protocol.messages import JointTrajPtFull, MotoMotionReply, Ping
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.fleet import Fleet, FleetCell
from pymotoros.runtime.traffic import OTHER, Traffic

from .peer import Peer, ctrl
from .support import LOCAL

Samples = dict[tuple[str, tuple[tuple[str, str], ...]], float]


def parse(text: str) -> Samples:
    out: Samples = {}
    for family in text_string_to_metric_families(text):
        for sample in family.samples:
            out[(sample.name, tuple(sorted(sample.labels.items())))] = sample.value
    return out


def value(samples: Samples, name: str, **labels: str) -> float:
    return samples.get((name, tuple(sorted(labels.items()))), 0.0)


@pytest.fixture
async def sim(controller: VirtualController) -> AsyncIterator[SimulatorApp]:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as app:
        yield app


async def scrape(port: int | None) -> Samples:
    async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{port}", timeout=10) as client:
        r = await client.get("/metrics")
    assert r.status_code == 200
    assert r.headers["content-type"].startswith("text/plain")
    return parse(r.text)


async def test_counters_rise_with_traffic(sim: SimulatorApp) -> None:
    before = await scrape(sim.ports.http)
    peer = await Peer.connect(sim.ports.motion, Port.MOTION)
    try:
        for _ in range(3):
            await peer.request(Ping())
        result, _ = await ctrl(peer, MotionCommand.CHECK_QUEUE_CNT)
        assert result == ResultCode.SUCCESS
        # a point without trajectory mode: refused NOT_READY (5), a refusal by code
        refusal = await peer.request(JointTrajPtFull.for_joints(0, 0, 0.0, [0.0] * 6, [0.0] * 6))
        assert isinstance(refusal, MotoMotionReply)
        assert refusal.result != ResultCode.SUCCESS
        during = await scrape(sim.ports.http)
    finally:
        await peer.close()
    await sim.ticker.wait_ticks(5)
    after = await scrape(sim.ports.http)
    assert value(during, "pymotoros_connections", port="motion") == 1
    assert value(after, "pymotoros_connections", port="motion") == 0
    assert value(after, "pymotoros_requests_total", port="motion", type="PING") == 3
    assert (
        value(
            after, "pymotoros_replies_total", port="motion", subject="CHECK_QUEUE_CNT", result="0"
        )
        == 1
    )
    code = (str(refusal.result), str(refusal.subcode))
    assert value(after, "pymotoros_refusals_total", port="motion", result=code[0], subcode=code[1])
    assert value(after, "pymotoros_ticks_total") > value(before, "pymotoros_ticks_total") > 0
    count = value(after, "pymotoros_loop_lateness_seconds_count")
    assert count > value(before, "pymotoros_loop_lateness_seconds_count")
    assert value(after, "pymotoros_loop_lateness_seconds_bucket", le="+Inf") == count


async def test_every_alarm_is_counted_beyond_the_history(sim: SimulatorApp) -> None:
    """120 alarms between two scrapes count 120, though the history keeps 100 (issue 28:
    the count was derived from the history and stopped at its length)."""
    before = await scrape(sim.ports.http)
    for n in range(120):
        sim.controller.raise_alarm(8001, n % 100, f"alarm {n}")
    after = await scrape(sim.ports.http)
    assert len(sim.controller.alarm_history()) == 100  # the history is bounded
    raised = value(after, "pymotoros_alarms_total") - value(before, "pymotoros_alarms_total")
    assert raised == 120
    sim.controller.raise_error(3, 0, "one more")
    again = await scrape(sim.ports.http)
    assert value(again, "pymotoros_alarms_total") == value(after, "pymotoros_alarms_total") + 1


async def test_alarms_pfl_and_fsu_are_counted(sim: SimulatorApp) -> None:
    controller = sim.controller
    assert isinstance(controller, VirtualController)
    before = await scrape(sim.ports.http)
    controller.raise_alarm(8001, 0, "metrics test")
    controller.safety.fsu.set(joint_speed_pct=30)
    after = await scrape(sim.ports.http)
    assert value(after, "pymotoros_alarms_total") == value(before, "pymotoros_alarms_total") + 1
    assert value(after, "pymotoros_alarms_active") >= 1
    assert value(after, "pymotoros_fsu_switches_total") == 1
    assert "pymotoros_pfl_events_total" in {name for name, _ in after}
    again = await scrape(sim.ports.http)  # a second scrape counts nothing twice
    assert value(again, "pymotoros_alarms_total") == value(after, "pymotoros_alarms_total")


async def test_each_cell_of_a_fleet_is_labelled() -> None:
    cells = [
        FleetCell("left", VirtualController(), replace(LOCAL, http_port=0)),
        FleetCell("right", VirtualController(), replace(LOCAL, http_port=0)),
    ]
    async with Fleet(cells) as fleet:
        for app, name in zip(fleet.apps, ("left", "right"), strict=True):
            samples = await scrape(app.ports.http)
            assert value(samples, "pymotoros_ticks_total", cell=name) > 0
            assert value(samples, "pymotoros_connections", cell=name, port="state") == 0


@pytest.mark.fidelity("safe")  # exact answers made-up commands with stale replies
async def test_made_up_commands_and_types_are_counted_under_one_label(sim: SimulatorApp) -> None:
    """A client sending random commands (a fuzzer) must not grow the counters, nor the
    exported labels, by one per distinct value: a million fuzzed frames grew the twin by
    9 MiB that way, and the scrape with it."""
    peer = await Peer.connect(sim.ports.motion, Port.MOTION)
    try:
        for command in range(900_001, 900_041):  # 40 distinct commands MotoROS does not know
            result, _ = await ctrl(peer, command)
            assert result == ResultCode.INVALID
    finally:
        await peer.close()
    traffic = Traffic()
    for msg_type in range(5_000, 5_040):
        traffic.request(msg_type)
    traffic.request(int(MsgType.PING))
    assert traffic.requests == {OTHER: 40, int(MsgType.PING): 1}
    samples = await scrape(sim.ports.http)
    subjects = {
        dict(labels)["subject"]
        for name, labels in samples
        if name == "pymotoros_replies_total" and dict(labels)["port"] == "motion"
    }
    assert "other" in subjects
    assert not any(s.isdigit() for s in subjects), subjects
    other = value(samples, "pymotoros_replies_total", port="motion", subject="other", result="3")
    assert other == 40
