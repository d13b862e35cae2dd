"""Set joint values and move: joint 5 (B axis) to -1.57 rad, the others to 0.

The MoveIt way is ``joint_values = group.get_current_joint_values()``, change
``joint_values[4]``, ``group.set_joint_value_target(joint_values)``, ``group.go()``.

    python examples/joint_values.py --host 192.168.1.31
"""

from __future__ import annotations

import argparse
import os

from pymotoros.client import SyncRobotClient


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
        robot.enable()
        joint_values = list(robot.current_positions())  # at rest, from feedback
        print("current:", ", ".join(f"{v:+.4f}" for v in joint_values))
        joint_values[:] = [0.0] * len(joint_values)
        joint_values[4] = -1.57  # joint 5, radians
        result = robot.move_joints(joint_values, speed_scale=0.5)
        print("reached:", ", ".join(f"{v:+.4f}" for v in result.final_positions))
        print(f"planned {result.trajectory.duration:.2f} s, took {result.elapsed_s:.2f} s")


if __name__ == "__main__":
    main()
