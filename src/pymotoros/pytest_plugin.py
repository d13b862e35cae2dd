"""A pytest plugin: the ``pymotoros_twin`` fixture, a started twin on OS-chosen ports.

Installing pymotoros registers it with pytest (a ``pytest11`` entry point): there is
nothing to enable, and adding it again (``pytest_plugins = [...]`` or ``-p``) is an
error. Because every pytest run of anyone with pymotoros installed loads this module,
importing it is cheap and does nothing: the controller and the servers are imported by
the fixture, when a test asks for a twin::

    def test_my_driver(pymotoros_twin):
        drive_robot("127.0.0.1", pymotoros_twin.motion, pymotoros_twin.state)

Each test gets its own twin: the real servers (motion, state, IO and, with
``http=True``, the control API) on 127.0.0.1 port 0 around a fresh
:class:`~pymotoros.controller.VirtualController` on the real clock, run by a thread of
the test process with its own event loop, so synchronous and asynchronous tests alike
can use it, and stopped after the test. Every port is chosen by the OS, so it works
under pytest-xdist (``pytest -n auto``): one twin per test, in every worker.

The cell comes from, in order: the test's ``@pytest.mark.pymotoros(cell=PATH)``
marker, its ``robot=``/``controller=`` names, the ``pymotoros_cell`` ini option (a
path relative to the rootdir), the default cell (HC10 on a YRC1000). The marker's
``fidelity="exact"|"safe"`` overrides the cell's (exact by default, docs/fidelity.md).

Client lint (issue 31): ``twin.lint_findings()`` are what the code under test did that a
real controller answers differently. With ``@pytest.mark.pymotoros(lint="error")`` (or
``pymotoros_lint = error`` in the ini file) a test that passed fails when there are any,
with the findings as its message; ``lint="ignore"`` (the default) leaves them to the test.

Like :mod:`pymotoros.testing`, this module sits on top of every layer; nothing in the
package imports it.
"""

from __future__ import annotations

import concurrent.futures
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final, TypeVar

import pytest

if TYPE_CHECKING:  # imported by the fixture, not by every pytest run (see above)
    import asyncio

    from pymotoros.controller import VirtualController
    from pymotoros.controller.cell import CellConfig
    from pymotoros.controller.lint import Finding

__all__ = ["RunningTwin", "pymotoros_twin"]

T = TypeVar("T")

START_TIMEOUT_S: Final = 30.0
"""Longest wait for the twin to listen (the control API's start-up is the slow part)."""

STOP_TIMEOUT_S: Final = 30.0
"""Longest wait for the twin's thread to finish after the test."""

MARKER: Final = "pymotoros"

LINT_MODES: Final = ("ignore", "error")
"""What a test with findings does: nothing (the test may assert on them), or fail."""


@dataclass(frozen=True)
class RunningTwin:
    """A twin serving on 127.0.0.1: its ports and, for the operator's side, its controller."""

    host: str
    motion: int
    state: int
    io: int
    http: int | None
    """The control API's port, or None (``@pytest.mark.pymotoros(http=True)`` starts it)."""
    controller: VirtualController
    """Live on the twin's thread: change it through :meth:`call` (thread-safe)."""
    _loop: asyncio.AbstractEventLoop
    _catch_up: Callable[[], object] | None = None
    """Brings an idle twin's controller up to date (idle batching) before :meth:`call`."""

    def call(self, fn: Callable[[VirtualController], T]) -> T:
        """Run ``fn(controller)`` on the twin's event loop, between two ticks; its result.

        For the operator's side in a test (``twin.call(lambda c: c.press_estop(True))``):
        the controller must not be touched from the test's thread directly.
        """
        future: concurrent.futures.Future[T] = concurrent.futures.Future()

        def run() -> None:
            try:
                if self._catch_up is not None:
                    self._catch_up()
                future.set_result(fn(self.controller))
            except BaseException as exc:  # handed to the caller
                future.set_exception(exc)

        self._loop.call_soon_threadsafe(run)
        return future.result(timeout=START_TIMEOUT_S)

    def lint_findings(self) -> list[Finding]:
        """The client lint's findings so far (``assert not twin.lint_findings()``)."""
        return self.call(lambda c: c.lint.findings())


class _TwinThread:
    """Runs a SimulatorApp in a thread with its own event loop until told to stop."""

    def __init__(self, cell: CellConfig, http: bool) -> None:
        self._cell = cell
        self._http = http
        self._started: concurrent.futures.Future[RunningTwin] = concurrent.futures.Future()
        self._stop: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread = threading.Thread(target=self._run, name="pymotoros-twin", daemon=True)

    def start(self) -> RunningTwin:
        self._thread.start()
        return self._started.result(timeout=START_TIMEOUT_S)

    def stop(self) -> None:
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(stop.set)
        self._thread.join(timeout=STOP_TIMEOUT_S)
        if self._thread.is_alive():
            raise RuntimeError(f"the pymotoros twin did not stop within {STOP_TIMEOUT_S} s")

    def _run(self) -> None:
        import asyncio

        try:
            asyncio.run(self._main())
        except BaseException as exc:  # reported to the test
            if not self._started.done():
                self._started.set_exception(exc)

    async def _main(self) -> None:
        import asyncio

        from pymotoros.controller import VirtualController
        from pymotoros.runtime.app import SimulatorApp, SimulatorConfig
        from pymotoros.runtime.tcp import ClientTasks

        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        motion_clients = ClientTasks()  # a scenario's drop_motion closes these
        controller = VirtualController(self._cell, motion_link=motion_clients)
        config = SimulatorConfig(
            host="127.0.0.1",
            motion_port=0,
            state_port=0,
            io_port=0,
            http_port=0 if self._http else None,
        )
        async with SimulatorApp(controller, config, motion_clients=motion_clients) as app:
            ports = app.ports
            self._started.set_result(
                RunningTwin(
                    "127.0.0.1",
                    ports.motion,
                    ports.state,
                    ports.io,
                    ports.http,
                    controller,
                    self._loop,
                    app.catch_up,
                )
            )
            await self._stop.wait()


def _cell_for(request: pytest.FixtureRequest) -> tuple[CellConfig, bool]:
    """The marker's cell, with its ``fidelity=`` if given (else the cell's, exact by default)."""
    marker = request.node.get_closest_marker(MARKER)
    kwargs = dict(marker.kwargs) if marker is not None else {}
    unknown = set(kwargs) - {"cell", "robot", "controller", "http", "fidelity", "lint"}
    if unknown:
        raise pytest.UsageError(
            f"@pytest.mark.{MARKER} got unknown arguments {sorted(unknown)}; "
            "use cell=PATH, robot=NAME, controller=NAME, http=True, "
            "fidelity='exact'|'safe', lint='error'|'ignore'"
        )
    cell, http = _named_cell(request, kwargs)
    if kwargs.get("fidelity") is None:
        return cell, http
    import dataclasses

    from pymotoros.models.fidelity import Fidelity

    try:
        fidelity = Fidelity.parse(kwargs["fidelity"], f"@pytest.mark.{MARKER}(fidelity=...)")
    except ValueError as exc:
        raise pytest.UsageError(str(exc)) from None
    return dataclasses.replace(cell, fidelity=fidelity), http


def _named_cell(
    request: pytest.FixtureRequest, kwargs: dict[str, object]
) -> tuple[CellConfig, bool]:
    from pymotoros.controller.cell import default_cell, load_cell

    http = bool(kwargs.get("http", False))
    names = {k: str(v) for k, v in kwargs.items() if k in ("robot", "controller")}
    path = kwargs.get("cell") or (None if names else request.config.getini("pymotoros_cell"))
    if path:
        resolved = Path(str(path))
        if not resolved.is_absolute():
            resolved = Path(str(request.config.rootpath)) / resolved
        return load_cell(resolved), http
    if names:
        return default_cell(names.get("controller", "yrc1000"), names.get("robot", "hc10")), http
    return default_cell(), http


ASYNCIO_LOOP_SCOPE_INI: Final = "asyncio_default_fixture_loop_scope"
"""pytest-asyncio's default event loop scope of async fixtures (its 0.24 and later).

pytest-asyncio 0.24+ warns when a project leaves it unset (a PytestDeprecationWarning,
an error under ``-W error``), so the example and the docs set it. pytest-asyncio 0.23,
or no pytest-asyncio at all, does not know the name, and pytest then warns "Unknown
config option" about the same line. The plugin declares the name where nothing else
has, so one configuration is clean with every pytest-asyncio the project allows and
without one. It does not choose a scope for anyone: which loop a user's own async
fixtures run in is theirs to set (a session-scoped fixture would change loops)."""


def _lint_mode(item: pytest.Item) -> str:
    marker = item.get_closest_marker(MARKER)
    mode = marker.kwargs.get("lint") if marker is not None else None
    if mode is None:
        mode = item.config.getini("pymotoros_lint") or "ignore"
    if mode not in LINT_MODES:
        raise pytest.UsageError(
            f"pymotoros lint mode {mode!r} is not one of {', '.join(LINT_MODES)}"
        )
    return str(mode)


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini(
        "pymotoros_cell",
        "cell TOML file (relative to the rootdir) for the pymotoros_twin fixture",
        default="",
    )
    parser.addini(
        "pymotoros_lint",
        "client lint findings of the pymotoros_twin fixture: ignore (default) or error "
        "(fail a test that passed)",
        default="ignore",
    )


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Iterator[None]:
    """With lint "error", a test of the twin that passed fails on the twin's findings."""
    result = yield
    funcargs = getattr(item, "funcargs", {})
    twin = funcargs.get("pymotoros_twin") if isinstance(funcargs, dict) else None
    if isinstance(twin, RunningTwin) and _lint_mode(item) == "error":
        findings = twin.lint_findings()
        if findings:
            from pymotoros.controller.lint import format_findings

            pytest.fail(format_findings(findings) + '\n(@pytest.mark.pymotoros(lint="error"))')
    return result


def pytest_load_initial_conftests(early_config: pytest.Config, parser: pytest.Parser) -> None:
    """Declare pytest-asyncio's loop-scope option if no plugin did (see above).

    By this hook every plugin named on the command line or installed (entry points) has
    declared its options; pytest checks the configuration's names only after
    collection. A later pytest-asyncio (a conftest's ``pytest_plugins``) declares it
    again, and its declaration wins.
    """
    try:
        early_config.getini(ASYNCIO_LOOP_SCOPE_INI)
    except ValueError:  # "unknown configuration value": no pytest-asyncio 0.24+ loaded
        parser.addini(
            ASYNCIO_LOOP_SCOPE_INI,
            "pytest-asyncio's default event loop scope of async fixtures; declared by "
            "pymotoros because no loaded pytest-asyncio (0.24+) knows it, so it does "
            "nothing here",
            default=None,
        )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        f"{MARKER}(cell=None, robot=None, controller=None, http=False, fidelity=None, "
        "lint=None): "
        "the cell and options of the pymotoros_twin fixture",
    )


@pytest.fixture
def pymotoros_twin(request: pytest.FixtureRequest) -> Iterator[RunningTwin]:
    """A started twin on OS-chosen ports, stopped after the test."""
    cell, http = _cell_for(request)
    runner = _TwinThread(cell, http)
    twin = runner.start()
    try:
        yield twin
    finally:
        runner.stop()
