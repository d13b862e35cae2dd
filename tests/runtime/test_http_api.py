"""The control API: state document, operator actions, and 4xx {"error": ...} for every mistake."""

from __future__ import annotations

import math
from dataclasses import replace

import httpx
import pytest

from pymotoros.controller import VirtualController
from pymotoros.controller.cell import cell_from_dict
from pymotoros.controller.lint import LintCode
from pymotoros.protocol.constants import MotionCommand
from pymotoros.runtime.app import SimulatorApp
from pymotoros.runtime.http_api import create_http_app

from .support import LOCAL, STATS


async def test_state_document_has_exactly_the_contract_keys(api: httpx.AsyncClient) -> None:
    r = await api.get("/api/state")
    assert r.status_code == 200
    doc = r.json()
    assert set(doc) == {
        "mode", "remote", "servo", "estop", "hold", "alarms", "motion_ready", "groups", "tick",
        "fsu", "pfl", "events", "motoros", "workspace", "ports",
    }  # fmt: skip
    assert doc["mode"] == "play"
    assert set(doc["groups"][0]) == {
        "name", "joint_names", "command_rad", "feedback_rad", "command_pulse", "queue", "tool",
        "tcp",
    }  # fmt: skip
    tcp = doc["groups"][0]["tcp"]
    assert set(tcp) == {"command", "feedback", "speed_mm_s"}
    assert len(tcp["command"]) == len(tcp["feedback"]) == 6
    assert set(tcp["speed_mm_s"]) == {"command", "feedback"}
    assert doc["tick"] == {
        "period_ms": 4.0,
        "count": 1000,
        "overruns": 2,
        "lateness_ms": {"p50": 0.05, "p99": 0.2, "max": 1.5},
    }


async def test_operator_actions(api: httpx.AsyncClient, controller: VirtualController) -> None:
    controller.set_servo(True)
    controller.run_ticks(200)  # servo power-up takes controller time
    assert (await api.get("/api/state")).json()["servo"] is True
    r = await api.post("/api/estop", json={"pressed": True})
    assert r.status_code == 200
    assert r.json()["estop"] is True
    assert r.json()["servo"] is False
    assert r.json()["alarms"] == []  # E-stop raises no alarm
    assert (await api.post("/api/estop", json={"pressed": False})).json()["estop"] is False
    assert (await api.post("/api/hold", json={"on": True})).json()["hold"] is True
    assert (await api.post("/api/hold", json={"on": False})).json()["hold"] is False
    assert (await api.post("/api/mode", json={"mode": "teach"})).json()["mode"] == "teach"
    assert (await api.post("/api/mode", json={"mode": "play"})).json()["mode"] == "play"
    assert (await api.post("/api/remote", json={"on": False})).json()["remote"] is False
    r = await api.post("/api/alarm", json={"code": 4107, "subcode": 2, "text": "OUT OF RANGE"})
    assert r.json()["alarms"] == [{"code": 4107, "subcode": 2, "text": "OUT OF RANGE"}]
    assert (await api.post("/api/reset")).json()["alarms"] == []
    assert (await api.post("/api/io", json={"address": 20010, "value": 1})).status_code == 200
    assert controller.read_io_bit(20010).value == 1
    r = await api.get("/api/io/20010")
    assert r.json() == {"address": 20010, "value": 1, "result_code": 0}
    r = await api.post("/api/io", json={"address": 1_000_007, "value": 512})
    assert controller.read_mregister(7).value == 512
    r = await api.post("/api/error", json={"code": 1234, "text": "operator error"})
    assert r.status_code == 200
    r = await api.post("/api/io/failure", json={"reads": True})
    assert controller.read_io_bit(20010).result_code == 1004


@pytest.mark.parametrize(
    ("method", "path", "body", "status", "fragment"),
    [
        ("GET", "/api/nope", None, 404, "no such endpoint: GET /api/nope"),
        ("GET", "/nowhere", None, 404, "no such endpoint"),
        ("GET", "/api/estop", None, 405, "method GET not allowed on /api/estop"),
        ("POST", "/api/estop", None, 422, "a JSON body is required"),
        ("POST", "/api/estop", {"pressed": "yes"}, 422, "pressed"),
        ("POST", "/api/estop", {"pressed": 1}, 422, "pressed"),
        ("POST", "/api/estop", {"pressed": True, "x": 1}, 422, "unknown field 'x'"),
        ("POST", "/api/mode", {"mode": "auto"}, 422, "mode"),
        ("POST", "/api/alarm", {"subcode": 1}, 422, "code: Field required"),
        ("POST", "/api/alarm", {"code": -5}, 422, "code"),
        ("POST", "/api/io", {"address": 20018, "value": 1}, 400, "20018"),
        ("POST", "/api/io", {"address": 20010, "value": 2}, 400, "0 or 1"),
        ("POST", "/api/io", {"address": 1_000_999, "value": 70000}, 422, "value"),
        ("POST", "/api/alarm", {"code": 99999}, 422, "code"),
        ("GET", "/api/io/20018", None, 400, "address 20018"),
        ("GET", "/api/io/abc", None, 422, "address"),
    ],
)
async def test_errors_are_4xx_with_a_message(
    api: httpx.AsyncClient,
    method: str,
    path: str,
    body: object,
    status: int,
    fragment: str,
) -> None:
    r = await api.request(method, path, json=body)
    assert r.status_code == status
    doc = r.json()
    assert set(doc) == {"error"}
    assert fragment in doc["error"]


# every POST endpoint, from a controller in trajectory mode; the expected motion_ready
# is what CHECK_MOTION_READY answers once MotoROS's status monitor has seen the action
_POSTS: list[tuple[str, dict[str, object] | None, bool]] = [
    ("/api/estop", {"pressed": True}, False),
    ("/api/estop", {"pressed": False}, True),
    ("/api/hold", {"on": True}, False),
    ("/api/hold", {"on": False}, True),
    ("/api/mode", {"mode": "teach"}, False),
    ("/api/mode", {"mode": "play"}, True),
    ("/api/remote", {"on": False}, False),
    ("/api/remote", {"on": True}, True),
    ("/api/servo", {"on": False}, False),
    ("/api/servo", {"on": True}, True),
    ("/api/alarm", {"code": 4107, "subcode": 1, "text": "TEST"}, False),
    ("/api/reset", None, True),
    ("/api/error", {"code": 1234}, True),
    ("/api/io", {"address": 50727, "value": 1}, True),  # eco mode: not tested by §4.1
    ("/api/io", {"address": 81702, "value": 1}, False),  # PFL stop: 5011
    ("/api/io", {"address": 50070, "value": 0}, False),  # the job stops
    ("/api/io", {"address": 20010, "value": 1}, True),
    ("/api/io/failure", {"reads": True, "writes": True}, True),
    ("/api/tick/reset", None, True),
]


@pytest.mark.parametrize(("path", "body", "expected"), _POSTS)
async def test_every_answer_has_the_motion_ready_of_a_fresh_read(
    api: httpx.AsyncClient,
    controller: VirtualController,
    path: str,
    body: dict[str, object] | None,
    expected: bool,
) -> None:
    """No answer is stale: it agrees with GET /api/state and with CHECK_MOTION_READY."""
    assert controller.wait_for(controller.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).ok
    controller.run_ticks(5)
    assert (await api.get("/api/state")).json()["motion_ready"] is True
    # the action lands between two status-monitor runs
    assert controller.motoros.next_monitor_ms > controller.time_ms
    r = await api.post(path, json=body) if body is not None else await api.post(path)
    assert r.status_code == 200, r.text
    answer = r.json()["motion_ready"]
    assert answer is expected
    assert (await api.get("/api/state")).json()["motion_ready"] is answer
    controller.motoros.status_update()  # the monitor's next run sees the action
    check = controller.wait_for(controller.motion_ctrl(0, MotionCommand.CHECK_MOTION_READY))
    assert check.ok is answer, check.detail
    assert controller.snapshot().motion_ready is answer


async def test_malformed_json_is_422(api: httpx.AsyncClient) -> None:
    r = await api.post(
        "/api/hold", content=b"{not json", headers={"content-type": "application/json"}
    )
    assert r.status_code == 422
    assert "not valid JSON" in r.json()["error"]


async def test_openapi_schema_lists_the_endpoints(api: httpx.AsyncClient) -> None:
    schema = (await api.get("/openapi.json")).json()
    for path in ("/api/state", "/api/estop", "/api/hold", "/api/mode", "/api/remote",
                 "/api/servo", "/api/alarm", "/api/reset", "/api/io", "/api/pfl", "/api/fsu",
                 "/api/scenario"):  # fmt: skip
        assert path in schema["paths"]


async def test_served_by_uvicorn_in_the_simulators_loop(controller: VirtualController) -> None:
    async with SimulatorApp(controller, replace(LOCAL, http_port=0)) as sim:
        assert sim.ports.http
        url = f"http://127.0.0.1:{sim.ports.http}"
        async with httpx.AsyncClient(base_url=url, timeout=5.0) as client:
            doc = (await client.get("/api/state")).json()
            assert doc["tick"]["period_ms"] == 4.0
            assert doc["tick"]["count"] >= 1
            r = await client.post("/api/hold", json={"on": True})
            assert r.json()["hold"] is True
            r = await client.get("/missing")
            assert r.status_code == 404
            assert "error" in r.json()
    assert controller.snapshot().hold is True


async def test_register_outputs_read_through_the_api() -> None:
    cell = cell_from_dict(
        {
            "groups": [{"robot": "hc10", "s1cxg": {"336": 1, "1290": 12}}],
            "initial": {"joints": {"R1": [0.5, 0.0, 0.0, 0.0, 0.0, 0.0]}},
        }
    )
    vc = VirtualController(cell)
    vc.tick()
    app = create_http_app(vc, lambda: STATS)
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://sim") as client:
        r = await client.get("/api/io/1000012")
    assert r.status_code == 200
    assert r.json()["value"] == round(math.degrees(0.5))  # S axis position in whole degrees


async def test_lint_findings_are_served_and_cleared(
    api: httpx.AsyncClient, controller: VirtualController
) -> None:
    assert (await api.get("/api/lint")).json() == {"findings": []}
    controller.lint.record(LintCode.UNKNOWN_COMMAND, "10.1.2.3:40000", 1.25, "command 7")
    controller.lint.record(LintCode.UNKNOWN_COMMAND, "10.1.2.3:40000", 2.5)
    (finding,) = (await api.get("/api/lint")).json()["findings"]
    assert finding["code"] == "unknown-command"
    assert finding["count"] == 2
    assert finding["first_s"] == 1.25
    assert finding["connection"] == "10.1.2.3:40000"
    assert finding["reference"] == "§3.1"
    assert "command 7" in finding["text"]
    assert finding["remedy"]
    assert (await api.delete("/api/lint")).json() == {"findings": []}
    assert (await api.get("/api/lint")).json() == {"findings": []}
    schema = (await api.get("/openapi.json")).json()
    answer = schema["paths"]["/api/lint"]["get"]["responses"]["200"]["content"]
    assert answer["application/json"]["schema"] == {"$ref": "#/components/schemas/LintModel"}
    assert "delete" in schema["paths"]["/api/lint"]
