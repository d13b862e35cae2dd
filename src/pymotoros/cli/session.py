"""How a robot command runs: where the robot is (from the common options), a client
connected to only the ports the command needs, errors as one line on stderr and a
documented exit code, and Ctrl-C/SIGTERM stopping a moving robot first.

Every command that talks to a robot (``status``, ``move``, ``io``, ``run`` ...) goes
through :func:`target_from_options` and :func:`run`; they drive a real MotoROS controller
or ``pymotoros sim`` through the same async client
(:class:`pymotoros.client.RobotClient`). A traceback is printed only with ``--debug``.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import signal
import sys
import traceback
from collections.abc import AsyncIterator, Callable, Coroutine
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, NoReturn, TypeVar

import click

from pymotoros.cli.options import EXIT_CONNECTION, EXIT_USAGE  # re-exported: all codes here
from pymotoros.cli.ports_file import ports_file_target, read_ports
from pymotoros.client import (
    ClientError,
    ConnectError,
    ConnectionLostError,
    GroupError,
    IoAddressError,
    ModelMismatchError,
    RequestTimeoutError,
    RobotClient,
)
from pymotoros.client.planning import PlanningError
from pymotoros.client.srdf import NamedPoseError
from pymotoros.errors import ConfigError, PymotorosError
from pymotoros.models.cell import CellModels
from pymotoros.protocol.constants import TCP_PORT_IO, TCP_PORT_MOTION, TCP_PORT_STATE

__all__ = [
    "EXIT_CODES_HELP",
    "EXIT_CONNECTION",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_REFUSED",
    "EXIT_TERMINATED",
    "EXIT_USAGE",
    "InputError",
    "Target",
    "connected",
    "echo_json",
    "fail",
    "read_ports_file",
    "run",
    "target_from_options",
]


EXIT_OK: Final = 0
EXIT_REFUSED: Final = 1
"""The robot refused or failed (NOT_READY, INVALID, IO result code, a move that did not finish)."""
EXIT_INTERRUPTED: Final = 130
"""Ctrl-C (SIGINT): a moving robot was stopped with STOP_MOTION first (128 + signal 2)."""
EXIT_TERMINATED: Final = 143
"""SIGTERM: a moving robot was stopped with STOP_MOTION first (128 + signal 15)."""


EXIT_CODES_HELP: Final = (
    "\b\nExit codes:\n"
    "  0    done\n"
    "  1    the robot refused or failed (the message says why and what to do)\n"
    "  2    bad usage: options, values, IO address, unknown pose or group, model mismatch\n"
    "  3    connection problem: refused, lost, or no answer in time\n"
    "  130  Ctrl-C (a moving robot is stopped first)\n"
    "  143  SIGTERM (a moving robot is stopped first)"
)

_T = TypeVar("_T")

_DEFAULT_PORTS: Final = {"motion": TCP_PORT_MOTION, "state": TCP_PORT_STATE, "io": TCP_PORT_IO}


@dataclass(frozen=True, slots=True)
class Target:
    """Where the robot is and what it is (from the common options)."""

    host: str
    motion_port: int
    state_port: int
    io_port: int
    controller: str
    robot: str
    timeout_s: float
    debug: bool
    cell: Path | CellModels | None = None
    """A cell file (``--config``), or the cell a ports file describes: controller and
    groups, instead of --controller/--robot."""
    http_port: int | None = None
    """The twin's control API port, when a ports file told it."""
    record: Path | None = None
    """pcapng file recording every frame of the session (--record)."""

    def client(self) -> RobotClient:
        return RobotClient(
            self.host,
            motion_port=self.motion_port,
            state_port=self.state_port,
            io_port=self.io_port,
            controller=self.controller,
            robot=self.robot,
            timeout_s=self.timeout_s,
            connect_timeout_s=self.timeout_s,
            cell=self.cell,
        )


@contextlib.asynccontextmanager
async def connected(
    target: Target, *, motion: bool, state: bool, io: bool
) -> AsyncIterator[RobotClient]:
    """A client connected to only the ports a command needs (MotoROS allows one motion and
    one IO connection: a command that does not need them leaves them to others)."""
    client = target.client()
    await client.connect(motion=motion, state=state, io=io)
    try:
        yield client
    finally:
        await client.close()


def read_ports_file(path: Path) -> dict[str, int]:
    """The ports a ``pymotoros sim --ports-file`` wrote (motion, state, io, http)."""
    return read_ports(path)


def target_from_options(kwargs: dict[str, Any]) -> Target:
    """The :class:`Target` the common options (:func:`~pymotoros.cli.options.robot_options`)
    name, popped from a command's ``kwargs``: a port given wins over the ports file's,
    which wins over MotoROS's; a bad ports file ends the command (exit 2)."""
    debug = kwargs.pop("debug")
    ports_file: Path | None = kwargs.pop("ports_file")
    try:
        told = ports_file_target(ports_file, kwargs.pop("cell"))
    except ConfigError as exc:
        fail(exc, debug=debug)
    from_file = told.ports

    def port(kind: str) -> int:
        given: int | None = kwargs.pop(f"{kind}_port")
        return given if given is not None else from_file.get(kind, _DEFAULT_PORTS[kind])

    cell = kwargs.get("cell_path")
    ctx = click.get_current_context(silent=True)
    named_by = f"the cell file {cell}" if cell is not None else told.named_by(ports_file)
    if named_by is not None and ctx is not None:
        for option in ("controller", "robot"):
            if ctx.get_parameter_source(option) is click.core.ParameterSource.COMMANDLINE:
                click.echo(f"warning: --{option} is ignored: {named_by} names the models", err=True)
    return Target(
        host=kwargs.pop("host"),
        motion_port=port("motion"),
        state_port=port("state"),
        io_port=port("io"),
        controller=kwargs.pop("controller"),
        robot=kwargs.pop("robot"),
        timeout_s=kwargs.pop("timeout_s"),
        debug=debug,
        cell=kwargs.pop("cell_path") or told.models,
        http_port=from_file.get("http"),
        record=kwargs.pop("record", None),
    )


def _exit_code(exc: BaseException) -> int:
    if isinstance(exc, (ConnectError, ConnectionLostError, RequestTimeoutError)):
        return EXIT_CONNECTION
    if isinstance(
        exc,
        (
            IoAddressError,
            PlanningError,
            NamedPoseError,
            ConfigError,
            GroupError,
            ModelMismatchError,
            InputError,
        ),
    ):
        return EXIT_USAGE
    if isinstance(exc, (ClientError, PymotorosError)):
        return EXIT_REFUSED
    return EXIT_REFUSED


class InputError(PymotorosError, ValueError):
    """A value the user typed that cannot be right (NaN, beyond a limit): exit code 2."""


def fail(exc: BaseException, *, debug: bool) -> NoReturn:
    """One line on stderr (a traceback too with --debug) and the error's exit code."""
    if debug:
        traceback.print_exception(exc)
    click.echo(f"error: {exc}", err=True)
    sys.exit(_exit_code(exc))


def run(
    target: Target, work: Callable[[], Coroutine[Any, Any, _T]], *, stoppable: bool = False
) -> _T:
    """Run ``work`` on a fresh event loop; errors become one line and an exit code.

    With ``stoppable`` (commands that move the robot), SIGTERM cancels ``work`` like
    Ctrl-C does: ``work`` sends STOP_MOTION on cancellation, then the process exits
    with :data:`EXIT_TERMINATED` (:data:`EXIT_INTERRUPTED` for Ctrl-C).
    """
    signals: list[int] = []

    async def main() -> _T:
        task = asyncio.current_task()
        loop = asyncio.get_running_loop()
        if stoppable and task is not None:

            def on_signal(sig: int) -> None:
                signals.append(sig)
                task.cancel()

            for sig in (signal.SIGTERM, signal.SIGINT):
                with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                    loop.add_signal_handler(sig, on_signal, sig)
        return await work()

    try:
        if target.record is None:
            return asyncio.run(main())
        from pymotoros.client.recorder import record_session

        with record_session(target.record):
            return asyncio.run(main())
    except (PymotorosError, OSError) as exc:
        fail(exc, debug=target.debug)
    except (KeyboardInterrupt, asyncio.CancelledError):
        code = EXIT_TERMINATED if signal.SIGTERM in signals else EXIT_INTERRUPTED
        click.echo("interrupted", err=True)
        sys.exit(code)


def echo_json(data: object) -> None:
    click.echo(json.dumps(data))
