"""The documentation runs: every code block of README.md and docs/*.md is executed, in
order, against a twin, with Sybil (the documentation-testing library) parsing the
Markdown.

One test per document. Its blocks share what a reader following the page shares: one
working directory (a fresh temporary one with ``examples`` linked into it, so paths in
the docs resolve and nothing is written into the repository), one Python namespace, one
running ``pymotoros sim``. Every failing block is reported with its line, not only the
first. Documents run two at a time (a module fixture), each still reported by its test.

How each kind of block runs:

* ``python``: in this process. Top-level ``await`` is allowed (one event loop per
  document). A block that defines ``test_*`` functions is a test file: it is written
  out and run by pytest in a subprocess. The client's default ports are those of the
  harness's sim while the block runs (``Ports``' defaults are rewritten), so
  ``SyncRobotClient("127.0.0.1", ...)`` reaches it as it reaches ``pymotoros sim``
  (only in blocks that name 127.0.0.1: the in-memory twin picks its own ports).
* ``sh`` and ``console`` (only the ``$ `` lines of a console block): each command in
  ``bash`` in the document's directory, and it must exit 0, or with one of the codes its
  comment names (``# exit 4``; ``# exit 0 clear, 1 refused, 4 warnings``), and print no
  traceback. Where a console block shows a command's output, the command must print it
  (``...`` stands for anything; of JSON shown, every key must be in what it prints).
  Commands find the twin through ``PYMOTOROS_PORTS_FILE`` (the file the harness's sim
  writes with ``--ports-file``), and ``python examples/...`` scripts through
  ``PYMOTOROS_MOTION_PORT``/``_STATE_PORT``/``_IO_PORT``. A robot command (``status``,
  ``move`` ...) with no sim running starts the default one first, as the README has the
  reader keep ``pymotoros sim`` running in a second terminal.
* ``toml``: parsed (a syntax error in a documented file fails).
* Blocks without a language, ``text`` and ``json`` are diagrams, output and schemas:
  not run.

What the harness recognises and replaces, so that the docs keep what a user types:

* ``pymotoros sim ...`` (foreground or ``&``) starts the harness's own sim with the
  same options but every port 0, a ports file (the one the command names, else its own),
  waits for its ready lines, and keeps it until the next ``pymotoros sim`` or the end of
  the document. A Python block starts the default one (HC10 on YRC1000) if none runs.
* ``127.0.0.1:8080`` and ``localhost:8080`` become the sim's HTTP port; ``curl`` gets
  ``--fail-with-body`` (an HTTP error fails the block); ``/tmp/`` becomes the document's
  directory; the docs' example controller address ``192.168.1.31`` becomes 127.0.0.1,
  the sim.
* ``export A=B`` sets the variables for the rest of the document.
* ``pymotoros status --watch`` without ``--count`` (it runs until Ctrl-C) gets SIGINT
  after its first frame and must end cleanly.
* ``python -m pip install ...`` becomes ``python -m pip show pymotoros`` (the package
  is installed already) and ``python -m pytest`` becomes ``python -m pytest --version``
  (the suite runs in CI; running it from inside itself would recurse).

The marker for blocks that are not run is an HTML comment, invisible on the rendered
page, on the line before the block::

    <!-- not-run: real robot -->

with one of the reasons in ``NOT_RUN_REASONS``: ``real robot`` (needs a controller),
``your files`` (needs the reader's own code or cell files), ``docker`` (needs a Docker
daemon, which CI lacks) or ``heavy`` (starts more processes than CI's two cores bear).
Any other reason is an error, so the marker cannot quietly hide a failing block. Setup a
reader does not need to see goes in Sybil's invisible blocks
(``<!-- invisible-code-block: python`` or ``: sh``, ended by ``-->``).
"""

from __future__ import annotations

import ast
import asyncio
import concurrent.futures
import contextlib
import inspect
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

sybil = pytest.importorskip("sybil", reason="sybil is not installed (the test extra has it)")

from sybil import Document, Example, Region, Sybil  # noqa: E402
from sybil.parsers.markdown import CodeBlockParser  # noqa: E402
from sybil.parsers.markdown.lexers import DirectiveInHTMLCommentLexer  # noqa: E402

from pymotoros.client.connection import Ports  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
BASH = shutil.which("bash") or "/bin/bash"
DOCS_TMP = "/tmp/"  # noqa: S108 - the docs' scratch paths, replaced by the test's own directory
# Not docs/api/: the API reference's MkDocs pages (``::: name`` lines); their only commands
# are `mkdocs serve`/`build`, which tests/test_api_reference.py runs and holds them to.
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
NOT_RUN_REASONS = frozenset({"real robot", "your files", "docker", "heavy"})
EXAMPLE_CONTROLLER = "192.168.1.31"
"""The controller address the docs use in examples: the harness's sim stands in for it."""
WORKERS = 2
"""Documents run at once."""
PYTHON_BLOCK = threading.Lock()
"""Held while a Python block runs (it changes the process's working directory)."""
COMMAND_TIMEOUT_S = 60.0
"""Bound of one documented command (a plan, a move, a replay take seconds)."""
READY_TIMEOUT_S = 60.0
"""Bound of a sim's start (Pinocchio and numpy imports on a busy 2-core machine)."""
STOP_TIMEOUT_S = 10.0
_READY = re.compile(r"pymotoros sim ready motion=(\S+) state=(\S+) io=(\S+) http=(\S+)")
_PORT_FLAGS = ("--motion-port", "--state-port", "--io-port", "--http-port", "--ports-file")
_EXIT_CODES = re.compile(r"\bexit (\d+)|,\s*(\d+) \w")


@dataclass
class SimProcess:
    process: subprocess.Popen[str]
    ports_file: Path
    ports: dict[str, int]
    log: Any

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(STOP_TIMEOUT_S)
        if self.process.stdout is not None:
            self.process.stdout.close()
        self.log.close()


@dataclass
class Harness:
    """What the blocks of one document share."""

    workdir: Path
    env: dict[str, str] = field(default_factory=dict)
    sim: SimProcess | None = None
    background: list[subprocess.Popen[bytes]] = field(default_factory=list)
    loop: asyncio.AbstractEventLoop = field(default_factory=asyncio.new_event_loop)
    not_run_next: str | None = None
    not_run: list[str] = field(default_factory=list)
    test_files: int = 0

    # --- the sim -------------------------------------------------------------------

    def start_sim(self, args: list[str]) -> SimProcess:
        """``pymotoros sim ARGS`` with every port 0 and a ports file."""
        self.stop_sim()
        ports_file = self.workdir / "harness-ports.json"
        kept: list[str] = []
        rest = iter(args)
        for arg in rest:
            if arg in _PORT_FLAGS:
                value = next(rest)
                if arg == "--ports-file":
                    ports_file = self.workdir / value
            elif arg != "&":
                kept.append(arg)
        ports_file.unlink(missing_ok=True)
        cells = max(1, kept.count("--config"))
        command = [sys.executable, "-m", "pymotoros", "sim", *kept]
        command += [flag for f in _PORT_FLAGS[:4] for flag in (f, "0")]
        command += ["--ports-file", str(ports_file)]
        log = (self.workdir / "sim.log").open("ab")
        process = subprocess.Popen(  # noqa: S603 - our own CLI
            command,
            cwd=self.workdir,
            env=self.environment(),
            stdout=subprocess.PIPE,
            stderr=log,
            text=True,
            start_new_session=True,
        )
        sim = SimProcess(process, ports_file, {}, log)
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            for _ in range(cells):
                assert process.stdout is not None
                line = pool.submit(process.stdout.readline).result(READY_TIMEOUT_S)
                if _READY.search(line) is None:
                    sim.stop()
                    log = (self.workdir / "sim.log").read_text(errors="replace")[-2000:]
                    raise AssertionError(f"{shlex.join(command)} did not start: {line!r}\n{log}")
        sim.ports = json.loads(ports_file.read_text())
        self.sim = sim
        self.env["PYMOTOROS_PORTS_FILE"] = str(ports_file)
        return sim

    def ensure_sim(self) -> SimProcess:
        return self.sim if self.sim is not None else self.start_sim([])

    def stop_sim(self) -> None:
        if self.sim is not None:
            self.sim.stop()
            self.sim = None

    def close(self) -> None:
        for process in self.background:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGTERM)
            process.wait(STOP_TIMEOUT_S)
        self.stop_sim()
        self.loop.close()

    # --- substitutions -------------------------------------------------------------

    def environment(self) -> dict[str, str]:
        env = {**os.environ, **self.env}
        src = str(ROOT / "src")
        env["PYTHONPATH"] = os.pathsep.join(p for p in (src, env.get("PYTHONPATH")) if p)
        return env

    def substitute(self, text: str) -> str:
        text = text.replace(EXAMPLE_CONTROLLER, "127.0.0.1").replace(DOCS_TMP, f"{self.workdir}/")
        if self.sim is not None and re.search(r"(127\.0\.0\.1|localhost):8080", text):
            text = re.sub(
                r"(127\.0\.0\.1|localhost):8080", f"127.0.0.1:{self.sim.ports['http']}", text
            )
        return text

    # --- markers -------------------------------------------------------------------

    def take_not_run(self, example: Example) -> bool:
        """Whether a ``not-run`` marker stands before this block (and forget it)."""
        reason, self.not_run_next = self.not_run_next, None
        if reason is not None:
            self.not_run.append(f"{example.path}:{example.line} ({reason})")
        return reason is not None


# --- shell ---------------------------------------------------------------------------


def shell_commands(source: str, console: bool) -> list[tuple[str, str | None]]:
    """The commands of a block, each with the output a console block shows after it
    (None: none shown): continuation lines joined, comments and blank lines dropped."""
    commands: list[tuple[str, str | None]] = []
    pending: str | None = None
    output: list[str] | None = None

    def close_output() -> None:
        nonlocal output
        if output is not None and commands:
            commands[-1] = (commands[-1][0], "\n".join(output) or None)
        output = None

    for raw in source.splitlines():
        line = raw.rstrip()
        if pending is not None:
            pending += " " + line.strip().removesuffix("\\").rstrip()
            if not line.endswith("\\"):
                commands.append((pending, None))
                pending, output = None, ([] if console else None)
            continue
        if console:
            if not line.startswith("$ "):
                if output is not None:
                    output.append(line)
                continue
            close_output()
            line = line[2:]
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if line.endswith("\\"):
            pending = line.removesuffix("\\").rstrip()
        else:
            commands.append((line, None))
            output = [] if console else None
    if pending is not None:
        commands.append((pending, None))
    close_output()
    return commands


def allowed_exit_codes(command: str) -> set[int]:
    """0, or the codes the command's comment names (``# exit 0 clear, 1 refused``)."""
    comment = re.search(r"\s#\s*(.*)$", command)
    if comment is None or "exit" not in comment.group(1):
        return {0}
    text = comment.group(1)[comment.group(1).index("exit") :]
    return {int(a or b) for a, b in _EXIT_CODES.findall(text)}


ROBOT_COMMANDS = frozenset(
    {"status", "enable", "disable", "servo", "reset", "move", "stop", "io", "mreg", "tool", "run"}
)
"""The commands that talk to a robot: with no sim running, the harness starts the default
one first (the README has the reader keep ``pymotoros sim`` running in a second terminal)."""


def run_command(harness: Harness, command: str, shown: str | None = None) -> str | None:
    """Run one documented command; a failure message, or None. ``shown``: the output a
    console block shows for it, which it must print (then any exit status is right: the
    block shows what happens, errors included; see ``_compare_output``)."""
    words = [w for w in shlex.split(command, comments=True) if w != "-q"]
    robot_command = words[:1] == ["pymotoros"] and words[1:2] and words[1] in ROBOT_COMMANDS
    if robot_command or re.search(r"(127\.0\.0\.1|localhost):8080", command):
        harness.ensure_sim()  # the twin a robot command or a curl line talks to
    command = harness.substitute(command)
    argv = shlex.split(command, comments=True)
    if not argv:
        return None
    background = argv[-1] == "&" or command.split("#")[0].rstrip().endswith("&")
    argv = [a for a in argv if a != "&"]
    program = [a for a in argv if a != "-q"]
    if program[:2] == ["pymotoros", "sim"]:
        harness.start_sim(argv[2 + (len(argv) - len(program)) :])
        return None
    if argv[0] == "export":
        for assignment in argv[1:]:
            name, _, value = assignment.partition("=")
            harness.env[name] = value
        return None
    if argv[:4] == ["python", "-m", "pip", "install"]:
        command = "python -m pip show pymotoros"
    elif argv == ["python", "-m", "pytest"]:
        command = "python -m pytest --version"
    command = re.sub(r"(^|\s)curl(\s)", r"\1curl --fail-with-body\2", command)
    env = harness.environment()
    if argv[0] == "python" and harness.sim is not None:
        for kind in ("motion", "state", "io"):
            env[f"PYMOTOROS_{kind.upper()}_PORT"] = str(harness.sim.ports[kind])
    if background:
        harness.background.append(
            subprocess.Popen(  # noqa: S603 - a documented command
                [BASH, "-c", command.split("#")[0].rstrip().removesuffix("&")],
                cwd=harness.workdir,
                env=env,
                start_new_session=True,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        return None
    if program[:2] == ["pymotoros", "status"] and "--watch" in argv and "--count" not in argv:
        return _interrupt_after_first_frame(harness, command, env)
    try:
        done = subprocess.run(  # noqa: S603 - a documented command
            [BASH, "-c", command],
            cwd=harness.workdir,
            env=env,
            capture_output=True,
            text=True,
            timeout=COMMAND_TIMEOUT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return f"`{command}` did not end within {COMMAND_TIMEOUT_S:.0f} s"
    if shown is not None:
        return _compare_output(command, done.stdout.strip(), shown.strip())
    expected = allowed_exit_codes(command)
    if done.returncode not in expected or "Traceback" in done.stderr:
        return (
            f"`{command}` exited {done.returncode} (expected {sorted(expected)})\n"
            f"stdout: {done.stdout[-1500:]}\nstderr: {done.stderr[-1500:]}"
        )
    return None


def _json_keys(value: Any) -> set[str]:
    if isinstance(value, dict):
        return set(value) | {k for v in value.values() for k in _json_keys(v)}
    if isinstance(value, list):
        return {k for v in value for k in _json_keys(v)}
    return set()


def _compare_output(command: str, printed: str, shown: str) -> str | None:
    """Shown JSON (abridged, with values of the moment): every key it names must be in
    the printed JSON. Other output: the same text, ``...`` standing for anything."""
    if shown.startswith("{"):
        try:
            keys = _json_keys(json.loads(printed))
        except json.JSONDecodeError:
            return f"`{command}` printed no JSON:\n{printed[:1500]}"
        missing = sorted(set(re.findall(r'"(\w+)":', shown)) - keys)
        if missing:
            return f"`{command}`: the docs show keys it does not print: {missing}"
        return None
    pattern = ".*".join(re.escape(part) for part in shown.split("..."))
    if re.fullmatch(pattern, printed, re.DOTALL) is None:
        return f"`{command}` printed\n{printed[:1500]}\nbut the docs show\n{shown}"
    return None


def _interrupt_after_first_frame(harness: Harness, command: str, env: dict[str, str]) -> str | None:
    """A command documented as running until Ctrl-C: SIGINT once it has printed."""
    process = subprocess.Popen(  # noqa: S603 - a documented command
        [BASH, "-c", "exec " + command.split("#")[0]],
        cwd=harness.workdir,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stdout is not None
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        try:
            first = pool.submit(process.stdout.readline).result(COMMAND_TIMEOUT_S)
        except concurrent.futures.TimeoutError:
            first = ""
        process.send_signal(signal.SIGINT)
        try:
            _, err = process.communicate(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            return f"`{command}` did not end on Ctrl-C (SIGINT)"
    if not first or process.returncode not in (0, 130) or "Traceback" in err:
        return (
            f"`{command}`: first line {first!r}, exit {process.returncode} on Ctrl-C\n{err[-1500:]}"
        )
    return None


# --- Sybil parsers --------------------------------------------------------------------


class NotRunParser:
    """``<!-- not-run: REASON -->``: the next block is not run, for a listed reason."""

    def __init__(self, harness: Harness) -> None:
        self.harness = harness
        self.lexer = DirectiveInHTMLCommentLexer("not-run", arguments=".+?")

    def __call__(self, document: Document) -> Iterator[Region]:
        for region in self.lexer(document):
            region.parsed = str(region.lexemes["arguments"]).strip().rstrip("-").strip()
            region.evaluator = self.evaluate
            yield region

    def evaluate(self, example: Example) -> str | None:
        reason = str(example.parsed)
        if reason not in NOT_RUN_REASONS:
            return f"not-run: {reason!r} is not a reason (one of {sorted(NOT_RUN_REASONS)})"
        self.harness.not_run_next = reason
        return None


def shell_parser(harness: Harness, language: str) -> CodeBlockParser:
    def evaluate(example: Example) -> str | None:
        if harness.take_not_run(example):
            return None
        failures = [
            failure
            for command, shown in shell_commands(str(example.parsed), console=language == "console")
            if (failure := run_command(harness, command, shown)) is not None
        ]
        return "\n".join(failures) or None

    return CodeBlockParser(language, evaluate)


def python_parser(harness: Harness) -> CodeBlockParser:
    def evaluate(example: Example) -> str | None:
        if harness.take_not_run(example):
            return None
        source = str(example.parsed)
        if "127.0.0.1" in source or EXAMPLE_CONTROLLER in source:
            harness.ensure_sim()
        source = harness.substitute(source)
        if re.search(r"^(async )?def test_", source, re.MULTILINE):
            return _run_as_test_file(harness, source)
        real_sockets = "127.0.0.1" in source
        namespace = example.namespace
        namespace.setdefault("__name__", "__docs__")
        code = compile(
            "\n" * (example.line - 1) + source,
            str(example.path),
            "exec",
            flags=ast.PyCF_ALLOW_TOP_LEVEL_AWAIT,
        )
        defaults = _client_defaults(harness) if real_sockets else contextlib.nullcontext()
        with PYTHON_BLOCK, defaults, contextlib.chdir(harness.workdir):
            if code.co_flags & inspect.CO_COROUTINE:
                harness.loop.run_until_complete(eval(code, namespace))  # noqa: S307
            else:
                exec(code, namespace)  # noqa: S102 - the documentation's own code
        return None

    return CodeBlockParser("python", evaluate)


@contextlib.contextmanager
def _client_defaults(harness: Harness) -> Iterator[None]:
    """The client's default ports are the harness sim's while a block runs."""
    init: Any = Ports.__init__
    saved = init.__defaults__
    if harness.sim is not None:
        init.__defaults__ = tuple(harness.sim.ports[k] for k in ("motion", "state", "io"))
    try:
        yield
    finally:
        init.__defaults__ = saved


def _run_as_test_file(harness: Harness, source: str) -> str | None:
    harness.test_files += 1
    path = harness.workdir / f"test_docs_block_{harness.test_files}.py"
    path.write_text(source)
    done = subprocess.run(  # noqa: S603 - pytest on the documentation's test
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-W", "error", path.name],
        cwd=harness.workdir,
        env=harness.environment(),
        capture_output=True,
        text=True,
        timeout=COMMAND_TIMEOUT_S,
        check=False,
    )
    if done.returncode != 0:
        return f"pytest on the block exited {done.returncode}:\n{done.stdout[-3000:]}"
    return None


def toml_parser(harness: Harness) -> CodeBlockParser:
    def evaluate(example: Example) -> str | None:
        if harness.take_not_run(example):
            return None
        tomllib.loads(str(example.parsed))
        return None

    return CodeBlockParser("toml", evaluate)


# --- the test ---------------------------------------------------------------------------


@dataclass
class Outcome:
    failures: list[str]
    not_run: list[str]
    slowest: list[tuple[float, int]]


def run_document(path: Path, workdir: Path) -> Outcome:
    """Every block of one document, in order; every failure, not only the first."""
    workdir.mkdir(parents=True)
    (workdir / "examples").symlink_to(ROOT / "examples")
    harness = Harness(workdir)
    parsers = [
        NotRunParser(harness),
        python_parser(harness),
        shell_parser(harness, "sh"),
        shell_parser(harness, "console"),
        toml_parser(harness),
    ]
    failures: list[str] = []
    seconds: list[tuple[float, int]] = []
    try:
        for example in Sybil(parsers=parsers).parse(path):
            start = time.monotonic()
            try:
                example.evaluate()
            except Exception as exc:  # every block's failure is reported, not only the first
                failures.append(f"{path.relative_to(ROOT)}:{example.line}: {exc}")
            seconds.append((time.monotonic() - start, example.line))
    finally:
        harness.close()
    return Outcome(failures, harness.not_run, sorted(seconds)[-5:])


@pytest.fixture(scope="module")
def outcomes(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> dict[Path, Outcome]:
    """The selected documents, run two at a time (CI's two cores: most of the time goes
    to the commands' and sims' own processes). Python blocks take ``PYTHON_BLOCK`` in
    turn: they change the working directory and the client's default ports."""
    selected = [
        item.callspec.params["path"]
        for item in request.session.items
        if getattr(item, "originalname", None) == "test_the_documentation_runs"
    ]
    base = tmp_path_factory.mktemp("docs")
    with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
        futures = {
            path: pool.submit(run_document, path, base / f"{i}-{path.stem}")
            for i, path in enumerate(selected)
        }
        return {path: future.result() for path, future in futures.items()}


@pytest.mark.timeout(900)
@pytest.mark.parametrize("path", DOCUMENTS, ids=[str(p.relative_to(ROOT)) for p in DOCUMENTS])
def test_the_documentation_runs(path: Path, outcomes: dict[Path, Outcome]) -> None:
    outcome = outcomes[path]
    print("slowest blocks:", ", ".join(f"line {n} {s:.1f} s" for s, n in outcome.slowest))
    if outcome.not_run:
        print("not run:", *outcome.not_run, sep="\n  ")
    failures = outcome.failures
    assert not failures, "\n\n".join(failures)
