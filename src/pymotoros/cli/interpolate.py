"""``pymotoros interpolate``: a trajectory CSV to the pulse increments MotoROS would queue.

External contract::

    pymotoros interpolate TRAJ.csv --controller yrc1000 --robot hc10
                          [--pulses-per-rad P1,...,Pn] [-o OUT.csv]

Input: a header row, then ``time,p1..pn,v1..vn`` per point (s, rad, rad/s, ROS
order); the first row is the trajectory start (sequence 0) and the robot stands
exactly there. Output: ``time_ms,i1..in``, one row per increment-queue entry, pulse
increments in controller order. A point MotoROS would refuse ends the command with
exit code 1 and a one-line message; a malformed file or option with exit code 2.
"""

from __future__ import annotations

import csv
import logging
import math
import os
import sys
import time
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import IO, Any, Final

import click
import numpy as np

from pymotoros.cli.options import (
    BadInput,
    InputFile,
    controller_option,
    deg_option,
    number_list,
    output_option,
    robot_option,
)
from pymotoros.errors import ConfigError, TrajectoryRejectedError
from pymotoros.models import ControllerModel, GroupModel, controller_model, robot_model
from pymotoros.motion import GroupAxes, interpolate_arrays

logger = logging.getLogger(__name__)

FAST_CSV_BYTES: Final = 1 << 20
"""Files at least this large are read and written with pyarrow's C++ CSV engine when it
is installed (the ``csv`` extra): importing it costs ~0.2 s, which only pays off on
large files (issue 13: a 150,000-row file spent 1.65 s in Python's csv module)."""

TIMINGS_ENV: Final = "PYMOTOROS_INTERPOLATE_TIMINGS"
"""When set (to anything but empty), the command ends by printing one line to stderr:
``interpolate timings monotonic: start=… read=… check=… engine=… written=…``, the
``time.monotonic()`` at which each phase ended (``start``: the command begins, after
the interpreter and the imports). ``bench/bench_interpolate.py`` subtracts its own
clock to split a whole process into phases; the output is unchanged."""

EXIT_REJECTED: Final = 1
"""A point MotoROS would refuse (the message names point, axis, value, limit, subcode)."""


class _Rejected(click.ClickException):
    exit_code = EXIT_REJECTED


def read_trajectory(
    stream: IO[str], n: int, name: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times, positions, velocities) of a trajectory CSV with ``n`` axes.

    Errors name the row (1 = the header) and the column (1-based, with its role).
    """
    columns = 1 + 2 * n
    roles = ["time"] + [f"p{i}" for i in range(1, n + 1)] + [f"v{i}" for i in range(1, n + 1)]
    reader = csv.reader(stream)
    header = next(reader, None)
    if header is None:
        raise click.BadParameter(f"{name} is empty; it needs a header row", param_hint="TRAJ.csv")
    if header and all(_is_number(cell) for cell in header):
        raise click.BadParameter(
            f"{name} row 1 holds numbers, not column names: the first row must be a header "
            f"({','.join(roles)}); add it above the start point",
            param_hint="TRAJ.csv",
        )
    if len(header) != columns:
        raise click.BadParameter(
            f"{name} row 1 (header): {len(header)} columns, expected {columns} "
            f"({', '.join(roles)})",
            param_hint="TRAJ.csv",
        )
    rows: list[list[float]] = []
    for number, row in enumerate(reader, start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != columns:
            raise click.BadParameter(
                f"{name} row {number}: {len(row)} columns, expected {columns} "
                f"(time, {n} positions, {n} velocities)",
                param_hint="TRAJ.csv",
            )
        values = []
        for col, cell in enumerate(row):
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise click.BadParameter(
                    f"{name} row {number}, column {col + 1} ({roles[col]}): "
                    f"{cell.strip()!r} is not a finite number",
                    param_hint="TRAJ.csv",
                )
            values.append(value)
        rows.append(values)
    if not rows:
        raise click.BadParameter(
            f"{name} has no points after the header; the first row is the start point",
            param_hint="TRAJ.csv",
        )
    data = np.array(rows, dtype=np.float64)
    return data[:, 0], data[:, 1 : n + 1], data[:, n + 1 :]


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


MAX_WARNINGS: Final = 5
"""Warnings printed about impossible points before the rest are only counted."""


def impossible_points(
    times: np.ndarray, pos: np.ndarray, group: GroupModel, deg: bool
) -> list[str]:
    """Points beyond the model's joint limits, or steps faster than its joint speeds.

    MotoROS checks neither (it checks the velocity fields, not the implied step), so a
    typo like 9 rad or 2 rad in 10 ms would be interpolated as given: say so.
    """
    unit, speed = ("deg", "deg/s") if deg else ("rad", "rad/s")
    scale = math.degrees(1.0) if deg else 1.0
    found: list[str] = []
    dt = np.diff(times)
    for j, axis in enumerate(group.axes):
        u, s, k = ("m", "m/s", 1.0) if axis.linear else (unit, speed, scale)
        for i in np.flatnonzero((pos[:, j] < axis.lower) | (pos[:, j] > axis.upper)):
            found.append(
                f"point {i}: {axis.name} = {pos[i, j] * k:.4g} {u} is beyond its limits "
                f"[{axis.lower * k:.4g}, {axis.upper * k:.4g}] {u}"
            )
        with np.errstate(divide="ignore", invalid="ignore"):
            rate = np.abs(np.diff(pos[:, j])) / dt
        for i in np.flatnonzero(rate > axis.max_velocity):
            found.append(
                f"point {i + 1}: {axis.name} moves {abs(pos[i + 1, j] - pos[i, j]) * k:.4g} {u} "
                f"in {dt[i]:.4g} s ({rate[i] * k:.4g} {s}), above its maximum "
                f"{axis.max_velocity * k:.4g} {s}"
            )
    return found


def read_trajectory_fast(path: Path, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """:func:`read_trajectory` with pyarrow for a well-formed file, or None (then the
    Python reader runs and gives the same values or the precise error).

    Both parse every number to the nearest double (pyarrow uses a correctly rounded
    parser, as ``float()``), so the values are the same. Anything unusual (a wrong column
    count, a cell pyarrow will not parse, a non-finite value, no rows) falls back.
    """
    try:
        import pyarrow as pa  # optional, and slow to import
        from pyarrow import csv as pacsv
    except ImportError:
        return None
    names = [f"c{i}" for i in range(1 + 2 * n)]
    try:
        table = pacsv.read_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=1, column_names=names),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(names, pa.float64()), strings_can_be_null=False
            ),
            parse_options=pacsv.ParseOptions(ignore_empty_lines=True),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError, OSError):
        return None
    if table.num_rows == 0 or any(column.null_count for column in table.columns):
        return None
    # Copied straight out of Arrow's buffers, one column per row of ``data``: to_numpy()
    # would import pandas if it is installed (~0.3 s), for nothing.
    data = np.empty((len(names), table.num_rows), dtype=np.float64)
    for j, column in enumerate(table.columns):
        row = 0
        for chunk in column.chunks:
            size = len(chunk)
            if not size:
                continue
            values = chunk.buffers()[1]
            data[j, row : row + size] = np.frombuffer(
                values, dtype=np.float64, count=size, offset=chunk.offset * 8
            )
            row += size
    if not np.isfinite(data).all():
        return None
    with path.open(encoding="utf-8", newline="") as stream:  # the header's column count
        header = next(csv.reader(stream), None)
    if header is None or len(header) != 1 + 2 * n or all(_is_number(c) for c in header):
        return None  # no header: the Python reader says so
    return data[0], data[1 : n + 1].T, data[n + 1 :].T


FLUSH_ENTRIES: Final = 1 << 16
"""Entries handed to the writer thread at a time: large enough that pyarrow's per-call
cost is negligible, small enough that writing starts early."""


class BlockWriter:
    """Writes the increments with pyarrow's CSV writer on a thread of its own, block by
    block while the engine computes the next ones (the engine's ``on_block``).

    pyarrow formats the integers without holding the GIL, so on two cores writing costs
    little wall time on top of the engine (issue 13). Nothing is opened or written before
    the first block, i.e. before every point has passed MotoROS's checks: a refused
    trajectory leaves no output, as on the Python path.
    """

    def __init__(self, sink: IO[bytes] | Path, n: int) -> None:
        import pyarrow as pa  # optional, and slow to import
        from pyarrow import csv as pacsv

        self._pa, self._pacsv = pa, pacsv
        self._target = sink
        self._n = n
        self._schema = pa.schema([(f"c{j}", pa.int64()) for j in range(n + 1)])
        self._sink: Any = None
        self._writer: Any = None
        self._pool: ThreadPoolExecutor | None = None
        self._pending: list[Future[None]] = []
        self._written = 0

    @classmethod
    def create(cls, sink: IO[bytes] | Path, n: int) -> BlockWriter | None:
        """A writer, or None when pyarrow is not installed (the Python writer then runs)."""
        try:
            return cls(sink, n)
        except ImportError:
            return None

    def block(self, time_ms: np.ndarray, increments: np.ndarray, done: int) -> None:
        """The engine's ``on_block``: entries ``[0, done)`` are final."""
        if done - self._written >= FLUSH_ENTRIES:
            self._submit(time_ms, increments, done)

    def finish(self, time_ms: np.ndarray, increments: np.ndarray) -> None:
        """Write what is left and wait until everything is written (errors raise here)."""
        self._submit(time_ms, increments, len(time_ms))
        if self._pool is not None:
            self._pool.shutdown(wait=True)
        for future in self._pending:
            future.result()
        self._writer.close()
        self.close()

    def close(self) -> None:
        """Stop the thread (dropping blocks not yet written) and close a file opened here;
        once is enough, more is harmless."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
        sink, self._sink = self._sink, None
        if sink is None:
            return
        if isinstance(self._target, Path):
            sink.close()
        else:
            sink.flush()

    def _submit(self, time_ms: np.ndarray, increments: np.ndarray, done: int) -> None:
        if self._pool is None:
            pa = self._pa
            self._sink = (
                pa.OSFile(str(self._target), "wb")
                if isinstance(self._target, Path)
                else self._target
            )
            names = ["time_ms", *(f"i{i}" for i in range(1, self._n + 1))]
            self._sink.write((",".join(names) + "\n").encode())
            options = self._pacsv.WriteOptions(include_header=False)
            self._writer = self._pacsv.CSVWriter(self._sink, self._schema, write_options=options)
            self._pool = ThreadPoolExecutor(1, thread_name_prefix="pymotoros-csv")
        lo, self._written = self._written, done
        if done > lo:
            job = self._pool.submit(self._write, time_ms[lo:done], increments[lo:done])
            self._pending.append(job)

    def _write(self, time_ms: np.ndarray, increments: np.ndarray) -> None:
        pa = self._pa
        size = len(time_ms)
        # Arrow arrays over the numpy memory (pa.array would import numpy.ma, ~12 ms).
        columns = [
            pa.Array.from_buffers(pa.int64(), size, [None, pa.py_buffer(column)])
            for column in (
                np.ascontiguousarray(time_ms, dtype=np.int64),
                *np.ascontiguousarray(increments.T, dtype=np.int64),
            )
        ]
        self._writer.write_table(pa.Table.from_arrays(columns, schema=self._schema))


def write_increments(stream: IO[str], time_ms: np.ndarray, increments: np.ndarray) -> None:
    n = increments.shape[1]
    stream.write(",".join(["time_ms", *(f"i{i}" for i in range(1, n + 1))]) + "\n")
    table = np.column_stack((time_ms, increments))
    stream.writelines(",".join(map(str, row)) + "\n" for row in table.tolist())


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("traj", metavar="TRAJ.csv", type=InputFile("trajectory CSV"))
@controller_option("controller_name")
@robot_option("robot_name", note="Robots of a single control group only (not sda10f).")
@click.option(
    "--pulses-per-rad",
    "ratios",
    metavar="P1,...,Pn",
    help="Override the model's pulses per rad, one per axis in ROS order. The speed limits "
    "in rad/s stay the model's.",
)
@output_option("Write the increments here instead of to stdout (says where on stderr)")
@deg_option("Positions and velocities of TRAJ.csv (deg/s)")
def interpolate(**options: Any) -> None:
    """Turn a trajectory CSV into the pulse increments MotoROS 1.9.12 would queue.

    TRAJ.csv has a header row, then one row per point: time,p1..pn,v1..vn (s, rad,
    rad/s, joints in ROS order). The first row is the trajectory start (sequence 0);
    the robot stands exactly there. The output has a header row time_ms,i1..in, then
    one row per increment-queue entry: the integer ms time and the pulse increment of
    each axis in controller order (for 7-axis arms E is the last column).

    A point MotoROS would refuse stops the command with exit code 1 and a message
    naming the point (0 = start), the axis, the value, the limit and the subcode.
    Robots with several control groups (sda10f) are not supported here.
    """
    marks: list[tuple[str, float]] | None = [] if os.environ.get(TIMINGS_ENV) else None
    try:
        _interpolate(**options, marks=marks)
    except click.BadParameter as exc:
        raise BadInput(exc.format_message()) from None
    if marks:
        text = " ".join(f"{name}={value:.6f}" for name, value in marks)
        click.echo(f"interpolate timings monotonic: {text}", err=True)


def _mark(marks: list[tuple[str, float]] | None, name: str) -> None:
    if marks is not None:
        marks.append((name, time.monotonic()))


def _single_group(robot_name: str, controller_name: str) -> tuple[GroupModel, ControllerModel]:
    """The robot's only group and the controller; a robot of several groups is refused."""
    try:
        robot = robot_model(robot_name)
        controller = controller_model(controller_name)
    except ConfigError as exc:
        raise click.BadParameter(str(exc)) from None
    if len(robot.groups) != 1:
        raise click.BadParameter(
            f"{robot.name} has {len(robot.groups)} control groups "
            f"({', '.join(g.name for g in robot.groups)}); pymotoros interpolate handles "
            "single-group robots only",
            param_hint="--robot",
        )
    if controller.type.value not in robot.controllers:
        logger.warning(
            "%s is not sold with a %s controller (known: %s); interpolating anyway",
            robot.name,
            controller.type.value,
            ", ".join(sorted(robot.controllers)),
        )
    return robot.groups[0], controller


def _read(traj: Path, n: int, large: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times, positions, velocities): pyarrow for a large well-formed file, else the
    Python reader (which gives the precise error)."""
    parsed = read_trajectory_fast(traj, n) if large else None
    if parsed is not None:
        return parsed
    try:
        with traj.open(newline="", encoding="utf-8") as stream:
            return read_trajectory(stream, n, traj.name)
    except UnicodeDecodeError as exc:
        raise BadInput(
            f"TRAJ.csv: {traj.name} is not UTF-8 text (byte {exc.start}: {exc.reason})"
        ) from None


def _warn_impossible(times: np.ndarray, pos: np.ndarray, group: GroupModel, deg: bool) -> None:
    warnings = impossible_points(times, pos, group, deg)
    for line in warnings[:MAX_WARNINGS]:
        click.echo(f"warning: {line}; check the file", err=True)
    if len(warnings) > MAX_WARNINGS:
        click.echo(f"warning: {len(warnings) - MAX_WARNINGS} more such points", err=True)


def _run_engine(
    parsed: tuple[np.ndarray, np.ndarray, np.ndarray],
    axes: GroupAxes,
    output: Path | None,
    writer: BlockWriter | None,
    marks: list[tuple[str, float]] | None,
) -> int:
    """Interpolate and write the increments (block by block with ``writer``); returns
    how many were written. A refused point: exit 1, nothing written."""
    try:
        time_ms, increments = interpolate_arrays(
            *parsed, axes, on_block=None if writer is None else writer.block
        )
        _mark(marks, "engine")
        if writer is not None:
            writer.finish(time_ms, increments)
    except TrajectoryRejectedError as exc:
        raise _Rejected(f"MotoROS would refuse {exc}") from None
    finally:
        if writer is not None:
            writer.close()  # after an error: stops the thread, closes the file
    if writer is None and output is None:
        write_increments(sys.stdout, time_ms, increments)
        sys.stdout.flush()
    elif writer is None and output is not None:
        with output.open("w", encoding="utf-8", newline="") as out:
            write_increments(out, time_ms, increments)
    return len(time_ms)


def _interpolate(
    traj: Path,
    controller_name: str,
    robot_name: str,
    ratios: str | None,
    output: Path | None,
    deg: bool,
    marks: list[tuple[str, float]] | None = None,
) -> None:
    _mark(marks, "start")
    group, controller = _single_group(robot_name, controller_name)
    n = group.num_axes
    pulses = number_list(
        ratios, n, hint="--pulses-per-rad", what="one per axis, ROS order", positive=True
    )
    try:
        axes = GroupAxes.from_model(group, controller, pulses)
    except ConfigError as exc:
        raise click.BadParameter(str(exc), param_hint="--pulses-per-rad") from None
    large = traj.stat().st_size >= FAST_CSV_BYTES
    times, pos, vel = _read(traj, n, large)
    _mark(marks, "read")
    if deg:
        angular = np.array([not a.linear for a in group.axes])
        pos = np.where(angular, np.radians(pos), pos)
        vel = np.where(angular, np.radians(vel), vel)
    _warn_impossible(times, pos, group, deg)
    _mark(marks, "check")
    if output is None:
        sys.stdout.flush()
    writer = (
        BlockWriter.create(sys.stdout.buffer if output is None else output, n) if large else None
    )
    written = _run_engine((times, pos, vel), axes, output, writer, marks)
    _mark(marks, "written")
    if output is not None:
        click.echo(
            f"wrote {written} increments ({n} axes, {len(times)} points) to {output}",
            err=True,
        )
