"""``pymotoros status``: the robot's state as a table or JSON, once or as it changes
(state port only: safe next to another client)."""

from __future__ import annotations

import asyncio
import math
import sys
from typing import Any

import click

from pymotoros.cli.cartesian import tcp_data, tcp_lines, tool_option, use_tool
from pymotoros.cli.live import (
    FrameWriter,
    OnceWriter,
    alarm_line,
    not_ready_reason,
    twin_alarm_texts,
)
from pymotoros.cli.options import group_option, robot_options, token_option
from pymotoros.cli.session import EXIT_CODES_HELP, connected, echo_json, run, target_from_options
from pymotoros.cli.sim_view import fetch_state_async, safety_data, safety_lines
from pymotoros.client import RobotClient
from pymotoros.client.state import RobotState

__all__ = ["status"]


def _status_data(
    client: RobotClient, state: RobotState, only: tuple[int, ...] = ()
) -> dict[str, Any]:
    groups = []
    for index, group in enumerate(client.robot.groups):
        if only and index not in only:
            continue
        fb = state.joints.get(index)
        groups.append(
            {
                "group": index,
                "name": group.name,
                "joints": list(group.joint_names),
                "positions": list(fb.positions) if fb else None,
                "velocities": list(fb.velocities) if fb and fb.velocities else None,
            }
            | tcp_data(client, index)
        )
    status = state.status.as_dict() if state.status else None
    if status is not None and state.status is not None and not state.status.motion_possible:
        status["not_ready_reason"] = not_ready_reason(state.status)
    return {"status": status, "groups": groups}


def _yes(value: bool | None, yes: str = "yes", no: str = "no") -> str:
    return "unknown" if value is None else (yes if value else no)


def _status_table(
    client: RobotClient,
    state: RobotState,
    only: tuple[int, ...] = (),
    alarm_texts: dict[int, str] | None = None,
    sim_state: dict[str, Any] | None = None,
) -> str:
    lines = [f"{client.robot.name} on {client.controller.type.value} at {client.host}"]
    st = state.status
    if st is not None:
        lines += [
            f"  mode              {st.mode.value.upper()}",
            f"  servo power       {_yes(st.drives_powered, 'on', 'off')}",
            f"  e-stop            {_yes(st.e_stopped, 'PRESSED', 'released')}",
            f"  alarm             {alarm_line(st, alarm_texts or {})}",
            f"  in motion         {_yes(st.in_motion)}",
            f"  motion possible   {_yes(st.motion_possible)}"
            + ("" if st.motion_possible else f"  ({not_ready_reason(st)})"),
        ]
    lines += safety_lines(sim_state, st.error_code if st is not None and st.in_error else None)
    width = max(len(n) for g in client.robot.groups for n in g.joint_names) + 2
    for index, group in enumerate(client.robot.groups):
        if only and index not in only:
            continue
        fb = state.joints.get(index)
        lines.append(f"  {group.name:<{width + 2}}{'rad':>10}{'deg':>10}{'rad/s':>10}")
        for j, name in enumerate(group.joint_names):
            if fb is None:
                lines.append(f"    {name:<{width}}{'-':>10}")
                continue
            pos = fb.positions[j]
            vel = fb.velocities[j] if fb.velocities else math.nan
            lines.append(f"    {name:<{width}}{pos:>10.4f}{math.degrees(pos):>10.2f}{vel:>10.4f}")
        lines += tcp_lines(client, index, width)
    return "\n".join(lines)


@click.command(epilog=EXIT_CODES_HELP)
@robot_options
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option(
    "--watch",
    is_flag=True,
    help="Keep showing the state as it changes (Ctrl-C ends): redrawn in place on a "
    "terminal, else printed when it changes (every update with --json).",
)
@click.option(
    "--live/--no-live",
    default=None,
    help="With --watch: redraw in place (default: when stdout is a terminal).",
)
@click.option(
    "--count",
    type=click.IntRange(1),
    default=None,
    help="With --watch: stop after this many updates (at --rate; an update that changes "
    "nothing is not printed again off a terminal, but counts).",
)
@click.option(
    "--rate",
    type=click.FloatRange(0.1, 40),
    default=4.0,
    show_default=True,
    help="With --watch: updates per second at most.",
)
@group_option(multiple=True)
@click.option(
    "--check-model",
    is_flag=True,
    help="Also compare the controller's DH parameters with the robot model (opens the "
    "motion port: not next to a moving client).",
)
@click.option(
    "--api",
    default=None,
    metavar="URL",
    help="pymotoros sim's control API (e.g. http://127.0.0.1:8080): adds PFL, FSU, alarm texts.",
)
@token_option
@tool_option
def status(
    as_json: bool,
    watch: bool,
    live: bool | None,
    count: int | None,
    rate: float,
    group: tuple[str, ...],
    check_model: bool,
    api: str | None,
    token: str | None = None,
    tool: int | None = None,
    **kwargs: Any,
) -> None:
    """Show the robot's state (state port only: safe next to another client)."""
    target = target_from_options(kwargs)

    async def work() -> None:
        async with connected(target, motion=check_model, state=True, io=False) as client:
            use_tool(client, tool)
            only = tuple(client.group_index(g) for g in group)
            state = await client.wait_for_state(target.timeout_s)
            if check_model:
                await client.check_dh_parameters()
            shown = 0
            last = -math.inf
            loop = asyncio.get_running_loop()
            texts: dict[int, str] = {}
            warned = OnceWriter()  # a refused alarm-text request: told once, not per frame
            redraw = watch and not as_json and (sys.stdout.isatty() if live is None else live)
            frames = FrameWriter(sys.stdout, live=redraw)
            try:
                while True:
                    if loop.time() - last >= 1.0 / rate:
                        last = loop.time()
                        st = state.status
                        if st is not None and st.in_error and st.error_code not in texts:
                            texts.update(
                                await asyncio.to_thread(
                                    twin_alarm_texts,
                                    target.host,
                                    target.http_port,
                                    token,
                                    warned.tell_once,
                                )
                            )
                        sim_state = await fetch_state_async(api, token) if api is not None else None
                        if as_json:
                            echo_json(_status_data(client, state, only) | safety_data(sim_state))
                        else:  # an unchanged frame is not printed again, but counts
                            frames.show(_status_table(client, state, only, texts, sim_state))
                        shown += 1
                        if not watch or (count is not None and shown >= count):
                            return
                    state = await client.tracker.next_state(target.timeout_s)
            finally:
                frames.close()

    run(target, work)
