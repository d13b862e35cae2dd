"""``pymotoros io`` and ``pymotoros mreg``: read or write an IO bit, a group of 8 bits
or an M-register (IO port only; ``mreg outputs`` is added in ``cli/register_outputs.py``)."""

from __future__ import annotations

from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

import click

from pymotoros.cli.options import robot_options
from pymotoros.cli.session import EXIT_CODES_HELP, connected, echo_json, run, target_from_options
from pymotoros.client import RobotClient

_T = TypeVar("_T")

__all__ = ["io", "io_read", "io_write", "mreg", "mreg_read", "mreg_write"]


@click.group(epilog=EXIT_CODES_HELP)
def io() -> None:
    """Read or write an IO bit (or a group of 8 with --group).

    \b
    Bit addresses end in the bit number 0..7: 10010 is general output OT#1,
    10011 OT#2 … A group address is the bit address without its last digit
    (1001 = bits 10010..10017). Leading zeros are ignored (decimal, not octal).
    MotoROS writes only general outputs, network inputs and the interface panel;
    addresses are checked against --controller's IO map before anything is sent.
    """


def _on_io_port(
    kwargs: dict[str, Any], call: Callable[[RobotClient], Coroutine[Any, Any, _T]]
) -> _T:
    """Run one request that needs only the IO port (MotoROS allows one IO client)."""
    target = target_from_options(kwargs)

    async def work() -> _T:
        async with connected(target, motion=False, state=False, io=True) as client:
            return await call(client)

    return run(target, work)


def _say_value(as_json: bool, key: str, number: int, value: int, text: str) -> None:
    """``{key: number, "value": value}`` with --json, else ``text``."""
    if as_json:
        echo_json({key: number, "value": value})
    else:
        click.echo(text)


_group_flag = click.option(
    "--group", "as_group", is_flag=True, help="ADDRESS is a group (byte) address."
)


_address_json = click.option(
    "--json", "as_json", is_flag=True, help='Print {"address": A, "value": V}.'
)


_number_json = click.option(
    "--json", "as_json", is_flag=True, help='Print {"number": N, "value": V}.'
)
"""The options the read and write commands of ``io`` and ``mreg`` share."""


@io.command("read", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("address", type=click.IntRange(0))
@_group_flag
@_address_json
def io_read(address: int, as_group: bool, as_json: bool, **kwargs: Any) -> None:
    """Read the IO bit (or group) at ADDRESS."""
    read = RobotClient.read_io_group if as_group else RobotClient.read_io_bit
    value = _on_io_port(kwargs, lambda client: read(client, address))
    _say_value(as_json, "address", address, value, str(value))


@io.command("write", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("address", type=click.IntRange(0))
@click.argument("value", type=click.IntRange(0))
@_group_flag
@_address_json
def io_write(address: int, value: int, as_group: bool, as_json: bool, **kwargs: Any) -> None:
    """Write VALUE (0/1, or 0..255 with --group) to the IO bit (or group) at ADDRESS."""
    write = RobotClient.write_io_group if as_group else RobotClient.write_io_bit
    _on_io_port(kwargs, lambda client: write(client, address, value))
    _say_value(as_json, "address", address, value, f"{address} = {value}")


@click.group(epilog=EXIT_CODES_HELP)
def mreg() -> None:
    """Read or write an M-register (read M000-M999, write M000-M559; 16 bits).

    Give the plain number (10 for M010), not 1000000 + n.
    """


@mreg.command("read", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0))
@_number_json
def mreg_read(number: int, as_json: bool, **kwargs: Any) -> None:
    """Read M-register NUMBER."""
    value = _on_io_port(kwargs, lambda client: client.read_mregister(number))
    _say_value(as_json, "number", number, value, str(value))


@mreg.command("write", epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0))
@click.argument("value", type=click.IntRange(0))
@_number_json
def mreg_write(number: int, value: int, as_json: bool, **kwargs: Any) -> None:
    """Write VALUE (0..65535) to M-register NUMBER."""
    _on_io_port(kwargs, lambda client: client.write_mregister(number, value))
    _say_value(as_json, "number", number, value, f"M{number:03d} = {value}")
