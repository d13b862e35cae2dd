"""The commands that send one request on the motion port and say what it did:
``enable``, ``disable``, ``stop``, ``reset``, ``servo``, ``tool``."""

from __future__ import annotations

from collections.abc import Callable, Coroutine
from typing import Any, Final

import click

from pymotoros.cli.options import group_option, robot_options
from pymotoros.cli.session import EXIT_CODES_HELP, connected, run, target_from_options
from pymotoros.client import ConnectionLostError, RobotClient
from pymotoros.client.errors import SECOND_MOTION_CLIENT
from pymotoros.protocol.constants import MAX_TOOL_NUMBER

__all__ = [
    "ONE_MOTION_CLIENT",
    "STOP_ELSEWHERE",
    "disable",
    "enable",
    "reset",
    "servo",
    "stop",
    "tool",
]


def _motion_command(
    kwargs: dict[str, Any],
    call: Callable[[RobotClient], Coroutine[Any, Any, object]],
    done: str,
) -> None:
    """Run one motion-port command that needs neither state nor IO, then say ``done``."""
    target = target_from_options(kwargs)

    async def work() -> None:
        async with connected(target, motion=True, state=False, io=False) as client:
            await call(client)
        click.echo(done)

    run(target, work)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def enable(**kwargs: Any) -> None:
    """Enter trajectory mode: START_TRAJ_MODE (servo on, INIT_ROS started)."""
    _motion_command(
        kwargs,
        RobotClient.start_trajectory_mode,
        "trajectory mode on: the robot accepts motion",
    )


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def disable(**kwargs: Any) -> None:
    """Leave trajectory mode: STOP_TRAJ_MODE."""
    _motion_command(kwargs, RobotClient.stop_trajectory_mode, "trajectory mode off")


ONE_MOTION_CLIENT: Final = (
    "MotoROS allows one motion client and closes a second motion connection while the "
    "robot moves, so `pymotoros stop` cannot take over. What works: Ctrl-C in the "
    "terminal of the moving command (or SIGTERM to it: it sends STOP_MOTION), HOLD or "
    "E-stop on the pendant, or for the twin its control API "
    '(POST /api/hold {{"on": true}} or /api/estop {{"pressed": true}} on {api})'
)
"""Reference §2.1: one motion connection; a new one is closed while increments are queued."""


STOP_ELSEWHERE: Final = (
    "That is why `pymotoros stop` cannot take over. SIGTERM to the moving command works "
    "as well (it sends STOP_MOTION), so does E-stop on the pendant and, for the twin, its "
    'control API (POST /api/hold {{"on": true}} or /api/estop {{"pressed": true}} on {api})'
)
"""What ``stop`` adds when the library's message already states the one-client rule and
the Ctrl-C/HOLD remedies (:data:`~pymotoros.client.errors.SECOND_MOTION_CLIENT`)."""


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def stop(**kwargs: Any) -> None:
    """Stop motion at once and clear every queue: STOP_MOTION.

    Only when no other client holds the motion connection: MotoROS refuses a second
    motion client while the robot moves (the message says what works instead).
    """
    target = target_from_options(kwargs)

    async def work() -> None:
        try:
            async with connected(target, motion=True, state=False, io=False) as client:
                await client.stop_motion()
        except ConnectionLostError as exc:
            api = (
                f"http://{target.host}:{target.http_port}"
                if target.http_port is not None
                else "the sim's --http-port"
            )
            rule_told = SECOND_MOTION_CLIENT in str(exc)  # say the rule once, not twice
            more = (STOP_ELSEWHERE if rule_told else ONE_MOTION_CLIENT).format(api=api)
            raise ConnectionLostError(f"{exc}. {more}") from exc
        click.echo("stopped")

    run(target, work)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
def reset(**kwargs: Any) -> None:
    """Reset alarms and cancel errors: RESET_ALARM (the cause must be gone first)."""
    _motion_command(kwargs, RobotClient.reset_alarm, "alarms and errors reset")


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("state", type=click.Choice(["on", "off"], case_sensitive=False))
def servo(state: str, **kwargs: Any) -> None:
    """Servo power on or off: START_SERVOS / STOP_SERVOS (trajectory mode is separate)."""
    if state.lower() == "on":
        _motion_command(kwargs, RobotClient.start_servos, "servo power on")
    else:
        _motion_command(kwargs, RobotClient.stop_servos, "servo power off")


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.argument("number", type=click.IntRange(0, MAX_TOOL_NUMBER))
@group_option()
def tool(number: int, group: str, **kwargs: Any) -> None:
    """Select the tool file NUMBER (0..63, §5.8) a group moves with: MOTO_SELECT_TOOL."""
    target = target_from_options(kwargs)

    async def work() -> None:
        async with connected(target, motion=True, state=False, io=False) as client:
            index = client.group_index(group)
            await client.select_tool(number, index)
        click.echo(f"group {index} ({client.robot.groups[index].name}) moves with tool {number}")

    run(target, work)
