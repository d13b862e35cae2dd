"""A task that survives a PFL contact: catch the typed 5011 error, enable again, finish.

On an HC robot a contact stops the arm and MotoROS refuses motion (NOT_READY 5011)
until trajectory mode is enabled again, which it refuses while the PFL signals are
still on. Try it against the twin with a contact 0.5 s into the first move::

    pymotoros sim --scenario examples/scenarios/pfl_contact.toml
    python examples/recover_from_pfl.py

Without a scenario the task simply runs through.
"""

from __future__ import annotations

import argparse
import os
import time

from pymotoros.client import NotReadyError, SyncRobotClient
from pymotoros.protocol.constants import NotReadySubcode

TASK = (
    (0.6, 0.2, 0.0, 0.0, -1.0, 0.0),
    (-0.4, 0.1, 0.2, 0.0, -1.2, 0.3),
    (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
)
"""The task: three joint goals (rad), in order."""
MAX_RECOVERIES = 3
"""Give up after this many contacts in one run: a cell that keeps colliding needs a person."""
RESUME_POLL_S = 0.1
"""How often to try enabling again while the PFL signals are still on (500 ms by default)."""
RESUME_ATTEMPTS = 100
"""10 s of retries at most."""


def enable_after_contact(robot: SyncRobotClient) -> None:
    """Enable trajectory mode again, waiting while the PFL stop signal is still on."""
    for _ in range(RESUME_ATTEMPTS):
        try:
            robot.enable()
        except NotReadyError as exc:
            if exc.reason is not NotReadySubcode.PFL_ACTIVE:
                raise
            time.sleep(RESUME_POLL_S)
        else:
            return
    raise RuntimeError(f"PFL still active after {RESUME_ATTEMPTS * RESUME_POLL_S:.0f} s")


def run_task(robot: SyncRobotClient) -> int:
    """Run :data:`TASK`; returns how many PFL contacts were recovered from."""
    robot.enable()
    recoveries = 0
    for goal in TASK:
        while True:
            try:
                robot.move_joints(goal, speed_scale=0.5)
                break
            except NotReadyError as exc:
                if exc.reason is not NotReadySubcode.PFL_ACTIVE or recoveries >= MAX_RECOVERIES:
                    raise
                recoveries += 1
                print(f"PFL contact ({exc.subcode}): enabling again and retrying the move")
                enable_after_contact(robot)
    return recoveries


def arguments() -> argparse.Namespace:
    env = os.environ.get
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=env("PYMOTOROS_HOST", "127.0.0.1"))
    parser.add_argument(
        "--motion-port", type=int, default=int(env("PYMOTOROS_MOTION_PORT", "50240"))
    )
    parser.add_argument("--state-port", type=int, default=int(env("PYMOTOROS_STATE_PORT", "50241")))
    parser.add_argument("--io-port", type=int, default=int(env("PYMOTOROS_IO_PORT", "50242")))
    return parser.parse_args()


def main() -> None:
    args = arguments()
    with SyncRobotClient(
        args.host, motion_port=args.motion_port, state_port=args.state_port, io_port=args.io_port
    ) as robot:
        recoveries = run_task(robot)
        final = robot.current_positions()
        print(
            f"task done after {recoveries} PFL recoveries at", ", ".join(f"{v:+.4f}" for v in final)
        )


if __name__ == "__main__":
    main()
