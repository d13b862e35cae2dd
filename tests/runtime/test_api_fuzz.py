"""An independent fuzzer of the control API's OpenAPI document (Schemathesis, issue 28).

Schemathesis reads ``/openapi.json`` from a live twin started with a token, and for every
operation generates requests from the schema (valid ones, and invalid ones it expects
refused with a 4xx), sends them with the token, and checks each answer: no 5xx, the
status, content type, headers and body as the document declares them. The twin is the
one ``pymotoros sim`` serves (SimulatorApp on 127.0.0.1 port 0, its own event loop in a
thread), so the Host check, the token guard and the error answers are all in the path.

Every check of Schemathesis runs, two with the statuses the document declares
(:data:`CHECKS`): a controller refuses valid requests its state does not allow with 400,
and a body beyond the control API's limit gets 413 whatever it holds.

Bounded: :data:`EXAMPLES` cases per operation (about 30 operations), no deadline per
case (a loaded CI machine), and the whole run in well under a minute.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from typing import Any

import pytest
import schemathesis  # the test extra (pyproject.toml): when missing, this fails loudly
from hypothesis import HealthCheck, given, settings
from hypothesis.errors import Unsatisfiable
from schemathesis import GenerationMode
from schemathesis.config import SchemathesisConfig
from schemathesis.specs.openapi.checks import positive_data_acceptance

from pymotoros.controller import VirtualController
from pymotoros.controller.actions import CONTROL_ACTIONS
from pymotoros.runtime.app import SimulatorApp, SimulatorConfig

TOKEN = "a-token-for-the-fuzzer-0123456789"  # noqa: S105 - a test token
AUTH = {"Authorization": f"Bearer {TOKEN}"}
EXAMPLES = 25
"""Cases per operation and mode (fewer where the inputs allow fewer): 305 valid and 400
invalid requests over 23 operations, about 15 s on a loaded 2-core machine."""
START_TIMEOUT_S = 30.0
REPORT_CHARS = 3000
CHECKS = {
    # valid data a controller may still refuse: 400 with its reason (servo on under
    # E-stop, a scenario file without events), 404 (an obstacle of that name is not there)
    "positive_data_acceptance": {"expected-statuses": ["2xx", "400", "404"]},
    # invalid data: the usual 4xx, and 413 for a body beyond the control API's limit
    "negative_data_rejection": {
        "expected-statuses": ["400", "401", "403", "404", "405", "406", "409", "413", "415", "422"]
    },
}
"""Schemathesis's checks as the control API's document declares its answers."""
BEYOND_THE_SCHEMA = frozenset(
    (spec.method, spec.path) for spec in CONTROL_ACTIONS if any(p.check for p in spec.params)
)
"""Actions with a parameter rule JSON Schema cannot say (an obstacle's name: not blank,
no '/'): a valid-looking value may get 422 with the rule's words."""


class LiveTwin:
    """A :class:`SimulatorApp` on its own event loop in a thread, for a blocking client."""

    def __init__(self, config: SimulatorConfig) -> None:
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, name="twin", daemon=True)
        self.config = config
        self.app: SimulatorApp | None = None

    def _run(self, coro: Any) -> Any:
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(START_TIMEOUT_S)

    def __enter__(self) -> SimulatorApp:
        self.thread.start()

        async def start() -> SimulatorApp:
            app = SimulatorApp(VirtualController(), self.config)
            return await app.__aenter__()

        self.app = self._run(start())
        return self.app

    def __exit__(self, *exc: object) -> None:
        try:
            if self.app is not None:
                self._run(self.app.__aexit__(None, None, None))
        finally:
            self.loop.call_soon_threadsafe(self.loop.stop)
            self.thread.join(START_TIMEOUT_S)
            self.loop.close()


@pytest.fixture(scope="module")
def twin_schema() -> Iterator[Any]:
    """The live twin's OpenAPI document, loaded by Schemathesis (with the token)."""
    config = SimulatorConfig(
        host="127.0.0.1", motion_port=0, state_port=0, io_port=0, http_port=0, token=TOKEN
    )
    with LiveTwin(config) as app:
        base = f"http://127.0.0.1:{app.ports.http}"
        config = SchemathesisConfig.from_dict({"checks": CHECKS})
        yield schemathesis.openapi.from_url(f"{base}/openapi.json", config=config, headers=AUTH)


def fuzz_operation(operation: Any, mode: Any) -> tuple[int, str | None]:
    """Run :data:`EXAMPLES` cases of one operation: (cases sent, the failure or None)."""
    ruled = (operation.method.upper(), operation.path) in BEYOND_THE_SCHEMA
    excluded = [positive_data_acceptance] if ruled else []
    sent = 0

    @given(case=operation.as_strategy(generation_mode=mode, headers=AUTH))
    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,  # the same cases on every run: a failure reproduces
        database=None,
    )
    def fuzz(case: Any) -> None:
        nonlocal sent
        sent += 1
        case.call_and_validate(headers=AUTH, excluded_checks=excluded)

    try:
        fuzz()
    except Unsatisfiable:  # nothing to break: no parameters, or any string is valid
        return sent, None
    except Exception as exc:
        what = str(exc)  # a case's body may be megabytes: its start says enough
        return sent, f"{operation.method.upper()} {operation.path}: {what[:REPORT_CHARS]}"
    return sent, None


@pytest.mark.parametrize("mode", [GenerationMode.POSITIVE, GenerationMode.NEGATIVE])
def test_the_control_api_matches_its_document(twin_schema: Any, mode: Any) -> None:
    """Every operation, valid data (must be answered as declared, never 5xx) and invalid
    data (must be refused with a declared 4xx)."""
    operations = [result.ok() for result in twin_schema.get_all_operations()]
    assert len(operations) > 15  # the whole document, not a sample
    results = [fuzz_operation(operation, mode) for operation in operations]
    failures = [failure for _, failure in results if failure is not None]
    assert not failures, "\n\n".join(failures)
    assert sum(sent for sent, _ in results) > len(operations)  # it did send cases
