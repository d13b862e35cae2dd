"""``pymotoros replay``: replay a recorded session against a twin or a controller, and diff.

The client side of the recording (every message the client sent, per connection,
with the original pacing; replies awaited as the original client did; the state
port read like it) goes to a fresh twin of the recorded cell started in this
process on ports the OS chooses, or to ``--against HOST``. Then it prints what
differs: replies (type, result, subcode) per request, reply delays beyond a
tolerance, and the final positions per joint within one encoder pulse. How replies
are paired and what is not compared: :mod:`pymotoros.client.replay`.

Exit codes: 0 the replies and final positions match, 1 they differ, 2 usage error
(bad option, unreadable recording, a cell whose byte order is not the recording's),
3 the target could not be reached.
"""

from __future__ import annotations

import asyncio
import json
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Final

import click

from pymotoros.cli.options import (
    EXIT_CONNECTION,
    EXIT_USAGE,
    BadInput,
    InputFile,
    config_option,
    controller_option,
    json_option,
    port_options,
    robot_option,
)
from pymotoros.client.recording import Recording, RecordingError, read_recording
from pymotoros.client.replay import (
    DEFAULT_TIMING_TOLERANCE_S,
    ReplayResult,
)
from pymotoros.client.replay import (
    replay as replay_session,
)
from pymotoros.controller.cell import CellConfig, default_cell, load_cell
from pymotoros.errors import ConfigError
from pymotoros.models import ControllerType
from pymotoros.protocol.constants import ByteOrder, Port

EXIT_MATCH: Final = 0
EXIT_DIFFERS: Final = 1

STARTUP_TIMEOUT_S: Final = 30.0
"""How long the in-process twin may take until MotoROS listens (its start-up checks)."""
STARTUP_POLL_TICKS: Final = 5
"""How often (interpolation ticks) the replay looks whether the twin's MotoROS listens."""

_ORDER_NAME: Final = {ByteOrder.LITTLE: "little-endian", ByteOrder.BIG: "big-endian (FS100)"}


def _cell(controller: str | None, robot: str | None, config: Path | None) -> CellConfig:
    if config is not None:
        if controller is not None or robot is not None:
            raise click.UsageError("give --config, or --controller/--robot, not both")
        return load_cell(config)
    return default_cell(controller or ControllerType.YRC1000.value, robot or "hc10")


def _pulse_tolerance(cell: CellConfig) -> dict[int, tuple[float, ...]]:
    """One encoder pulse per joint, per group (rad or m): "within a pulse"."""
    return {
        index: tuple(1.0 / axis.pulses_per_unit for axis in group.axes)
        for index, group in enumerate(cell.groups)
    }


async def _against_twin(
    recording: Recording, cell: CellConfig, timing_tolerance: float
) -> ReplayResult:
    """Start a fresh twin of ``cell`` in this process (127.0.0.1, OS-chosen ports, no
    control API), replay against it, stop it."""
    from pymotoros.controller import VirtualController
    from pymotoros.runtime.app import SimulatorApp, SimulatorConfig

    config = SimulatorConfig(
        host="127.0.0.1",
        motion_port=0,
        state_port=0,
        io_port=0,
        http_port=None,
        byte_order=cell.controller.byte_order,
    )
    app = SimulatorApp(VirtualController(cell), config)
    async with app:
        async with asyncio.timeout(STARTUP_TIMEOUT_S):
            while not app.motoros_listening:  # start-up checks of the cell (docs/sim.md)
                await app.ticker.wait_ticks(STARTUP_POLL_TICKS)
        ports = app.ports
        return await replay_session(
            recording,
            "127.0.0.1",
            {Port.MOTION: ports.motion, Port.STATE: ports.state, Port.IO: ports.io},
            pulse_tolerance=_pulse_tolerance(cell),
            timing_tolerance=timing_tolerance,
        )


def _fmt(summary: Mapping[str, object]) -> str:
    if summary.get("type") is None:
        return "no reply"
    parts = [str(summary["type"])]
    if summary.get("result") is not None:
        parts.append(f"result {summary['result']}")
    if summary.get("subcode") is not None:
        parts.append(f"subcode {summary['subcode']}")
    if summary.get("value") is not None:
        parts.append(f"value {summary['value']}")
    return " ".join(parts)


def _joints(values: Sequence[float] | None) -> str:
    return "-" if values is None else " ".join(f"{v:+.6f}" for v in values)


def _human(result: ReplayResult, target: str) -> str:
    lines = [
        f"replayed {result.requests} requests on {result.connections} connections against "
        f"{target}: recorded {result.recorded_duration:.3f} s, replayed "
        f"{result.replayed_duration:.3f} s"
    ]
    if result.differences:
        lines.append(f"replies: {len(result.differences)} differ")
        for d in result.differences:
            what = d.request_type
            if d.command is not None:
                what += f" {d.command.split(' (')[0]}"
            if d.sequence is not None:
                what += f" sequence {d.sequence}"
            lines.append(
                f"  request {d.request} ({d.port}, {what}, at {d.offset:.3f} s): "
                f"recorded {_fmt(d.recorded)}, replayed {_fmt(d.replayed)}"
            )
    else:
        lines.append(f"replies: all {result.requests} match")
    outliers = result.slow_or_fast
    delays = [t.difference for t in result.timings if t.difference is not None]
    worst = max((abs(d) for d in delays), default=0.0)
    lines.append(
        f"timing: {len(outliers)} of {len(delays)} reply delays differ by more than "
        f"{result.timing_tolerance * 1000:.0f} ms (largest difference {worst * 1000:.1f} ms)"
    )
    for t in outliers[:10]:
        lines.append(
            f"  request {t.request} ({t.port}, {t.request_type}): recorded "
            f"{(t.recorded_delay or 0.0) * 1000:.1f} ms, replayed "
            f"{(t.replayed_delay or 0.0) * 1000:.1f} ms"
        )
    if len(outliers) > 10:
        lines.append(f"  … and {len(outliers) - 10} more (--json lists them all)")
    if not result.positions:
        lines.append("final positions: no state connection in the recording")
    for p in result.positions:
        verdict = "within a pulse" if p.matches else "DIFFER"
        lines.append(f"final positions, group {p.group}: {verdict}")
        lines.append(f"  recorded {_joints(p.recorded)}")
        lines.append(f"  replayed {_joints(p.replayed)}")
    if result.settled is False:
        lines.append("  (the replayed robot was still moving when they were taken)")
    lines.append("MATCH" if result.matches else "DIFFER")
    return "\n".join(lines)


@click.command()
@click.argument("recording_path", type=InputFile("session recording (pcapng)"))
@click.option(
    "--against",
    "host",
    default=None,
    metavar="HOST",
    help="Replay against this controller (or a running `pymotoros sim`) instead of a "
    "fresh twin started for the replay.",
)
@port_options(env=False, defaults=True)
@controller_option("controller_name", unset="yrc1000, or the cell file's")
@robot_option("robot_name", unset="hc10, or the cell file's")
@config_option("config_path")
@click.option(
    "--timing-tolerance",
    type=click.FloatRange(0.0, min_open=True),
    default=DEFAULT_TIMING_TOLERANCE_S,
    show_default=True,
    help="Reply delays (s) further apart than this are listed; they do not make the replay differ.",
)
@json_option("the diff")
def replay(
    recording_path: Path,
    host: str | None,
    motion_port: int,
    state_port: int,
    io_port: int,
    controller_name: str | None,
    robot_name: str | None,
    config_path: Path | None,
    timing_tolerance: float,
    as_json: bool,
) -> None:
    """Replay the client side of RECORDING (pcapng from --record or `sim --record`).

    Against a fresh twin of the recorded cell (name it with --config, or --controller
    and --robot; default an HC10 on a YRC1000) or, with --against, a controller. Prints
    the replies that differ, the reply delays and the final positions. Exit codes: 0
    match, 1 differ, 2 usage error, 3 the target could not be reached.
    """
    try:
        recording = read_recording(recording_path)
        cell = _cell(controller_name, robot_name, config_path)
    except (RecordingError, ConfigError) as exc:
        raise BadInput(str(exc)) from exc
    order = recording.order
    if order is not None and order is not cell.controller.byte_order:
        raise click.UsageError(
            f"the recording is {_ORDER_NAME[order]} but the {cell.controller.type.value} "
            f"cell speaks {_ORDER_NAME[cell.controller.byte_order]}: name the recorded "
            "controller with --controller or --config"
        )
    try:
        if host is None:
            target = f"a fresh twin ({cell.source})"
            result = asyncio.run(_against_twin(recording, cell, timing_tolerance))
        else:
            target = f"{host}"
            result = asyncio.run(
                replay_session(
                    recording,
                    host,
                    {Port.MOTION: motion_port, Port.STATE: state_port, Port.IO: io_port},
                    pulse_tolerance=_pulse_tolerance(cell),
                    timing_tolerance=timing_tolerance,
                )
            )
    except ValueError as exc:
        raise click.UsageError(str(exc)) from exc
    except ConnectionError as exc:
        click.echo(f"Error: {exc}", err=True)
        sys.exit(EXIT_CONNECTION)
    if as_json:
        click.echo(json.dumps({"target": target, **result.as_json()}, indent=2))
    else:
        click.echo(_human(result, target))
    sys.exit(EXIT_MATCH if result.matches else EXIT_DIFFERS)


__all__ = ["EXIT_CONNECTION", "EXIT_DIFFERS", "EXIT_MATCH", "EXIT_USAGE", "replay"]
