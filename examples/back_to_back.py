"""Several moves back to back, with the async client.

Each move starts where the previous one settled, so none is refused for its start
position (3011); the named poses come from an SRDF, in an order of our choosing.

    python examples/back_to_back.py --host 192.168.1.31
"""

from __future__ import annotations

import argparse
import asyncio
import os
from pathlib import Path

from pymotoros.client import RobotClient

HERE = Path(__file__).resolve().parent


def arguments() -> argparse.Namespace:
    env = os.environ.get
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=env("PYMOTOROS_HOST", "127.0.0.1"))
    parser.add_argument(
        "--motion-port", type=int, default=int(env("PYMOTOROS_MOTION_PORT", "50240"))
    )
    parser.add_argument("--state-port", type=int, default=int(env("PYMOTOROS_STATE_PORT", "50241")))
    parser.add_argument("--io-port", type=int, default=int(env("PYMOTOROS_IO_PORT", "50242")))
    parser.add_argument("--srdf", type=Path, default=HERE / "hc10.srdf")
    return parser.parse_args()


async def main() -> None:
    args = arguments()
    async with RobotClient(
        args.host, motion_port=args.motion_port, state_port=args.state_port, io_port=args.io_port
    ) as robot:
        await robot.enable()
        for name in ("pick", "place", "ready", "home"):
            result = await robot.move_named(name, srdf=args.srdf)
            took, planned = result.elapsed_s, result.trajectory.duration
            busy, lag = result.stream.busy_replies, result.following.max_lag_s
            print(f"{name:<6} {took:.2f} s ({planned:.2f} s planned), {busy} BUSY, lag {lag:.3f} s")
        # Joint values straight after a named pose: again no waiting by hand.
        await robot.move_joints([0.3, 0.1, 0.2, 0.0, -1.0, 0.5])
        await robot.move_named("home")
        print("done")


if __name__ == "__main__":
    asyncio.run(main())
