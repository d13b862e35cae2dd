"""A hand-written Simple Message client with two bugs a real MotoROS punishes.

It works against a forgiving simulator, which is the trouble: it asks for a
MOTO_MOTION_CTRL command MotoROS does not have (the robot then sends its previous reply
again, which can look like a success), and it writes the prefix of a message separately
from the rest (a real controller answers the first piece INVALID/3001 and parses the
rest as a new message). The twin answers it, and records both as client lint findings:
``curl 127.0.0.1:8080/api/lint`` or the pendant's "Client lint" panel shows them.
"""

from __future__ import annotations

import argparse
import os
import socket
import struct
import time

PREFIX_GAP_S = 0.1
"""Between the prefix and the rest: long enough that they arrive in two reads."""
MOTO_MOTION_CTRL = 2001
REQUEST = 1
MADE_UP_COMMAND = 200199  # not in MotoROS's list (§3.1)
CHECK_QUEUE_CNT = 200102


def motion_ctrl(command: int) -> bytes:
    """A little-endian MOTO_MOTION_CTRL (YRC1000, DX200, DX100): prefix, header, body."""
    body = struct.pack("<3i10f", 0, 0, command, *([0.0] * 10))
    return struct.pack("<4i", 12 + len(body), MOTO_MOTION_CTRL, REQUEST, 0) + body


def main() -> None:
    env = os.environ.get
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=env("PYMOTOROS_HOST", "127.0.0.1"))
    parser.add_argument(
        "--motion-port", type=int, default=int(env("PYMOTOROS_MOTION_PORT", "50240"))
    )
    args = parser.parse_args()
    with socket.create_connection((args.host, args.motion_port), timeout=5) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.sendall(motion_ctrl(CHECK_QUEUE_CNT))
        sock.recv(1024)
        sock.sendall(motion_ctrl(MADE_UP_COMMAND))  # bug 1: a command MotoROS lacks
        sock.recv(1024)
        frame = motion_ctrl(CHECK_QUEUE_CNT)
        sock.sendall(frame[:4])  # bug 2: the prefix on its own
        time.sleep(PREFIX_GAP_S)
        sock.sendall(frame[4:])
        sock.recv(1024)
    print("done: see GET /api/lint")


if __name__ == "__main__":
    main()
