"""Visit the named poses of an SRDF file one after another, then go home.

The MoveIt way is ``group.set_named_target(name); group.go()`` for each
``group_state``; here each pose is one call, without ROS.

    python examples/named_poses.py --host 192.168.1.31 --srdf examples/hc10.srdf
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from pymotoros.client import SyncRobotClient, parse_srdf

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
    parser.add_argument("--speed-scale", type=float, default=0.5)
    return parser.parse_args()


def main() -> None:
    args = arguments()
    poses = parse_srdf(args.srdf)
    print(f"{len(poses)} named poses in {args.srdf.name}")
    with SyncRobotClient(
        args.host,
        motion_port=args.motion_port,
        state_port=args.state_port,
        io_port=args.io_port,
        robot="hc10",
    ) as robot:
        robot.enable()
        for pose in poses:
            result = robot.move_named(pose.name, srdf=args.srdf, speed_scale=args.speed_scale)
            values = ", ".join(f"{v:+.3f}" for v in result.final_positions)
            print(f"{pose.name:<10} reached [{values}] in {result.elapsed_s:.2f} s")
        robot.move_named("home", speed_scale=args.speed_scale)
        print("home")


if __name__ == "__main__":
    main()
