"""Read and write an IO signal, and an M-register.

General output OT#1 is bit address 10010 (OT#n = 10010 + 10·((n-1) // 8) + (n-1) % 8).
MotoROS writes only general outputs, network inputs and the interface panel.

    python examples/io_signal.py --host 192.168.1.31 --address 10010
"""

from __future__ import annotations

import argparse
import os

from pymotoros.client import IoAddressError, SyncRobotClient


def arguments() -> argparse.Namespace:
    env = os.environ.get
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=env("PYMOTOROS_HOST", "127.0.0.1"))
    parser.add_argument(
        "--motion-port", type=int, default=int(env("PYMOTOROS_MOTION_PORT", "50240"))
    )
    parser.add_argument("--state-port", type=int, default=int(env("PYMOTOROS_STATE_PORT", "50241")))
    parser.add_argument("--io-port", type=int, default=int(env("PYMOTOROS_IO_PORT", "50242")))
    parser.add_argument("--address", type=int, default=10010, help="bit address (OT#1 = 10010)")
    return parser.parse_args()


def main() -> None:
    args = arguments()
    with SyncRobotClient(
        args.host, motion_port=args.motion_port, state_port=args.state_port, io_port=args.io_port
    ) as robot:
        before = robot.read_io_bit(args.address)
        robot.write_io_bit(args.address, 1 - before)
        after = robot.read_io_bit(args.address)
        print(f"IO {args.address}: {before} -> {after}")

        robot.write_mregister(10, 1234)
        print(f"M010 = {robot.read_mregister(10)}")

        try:
            robot.write_io_bit(20010, 1)  # an external input: MotoROS refuses to write it
        except IoAddressError as exc:
            print(f"refused before sending: {exc}")


if __name__ == "__main__":
    main()
