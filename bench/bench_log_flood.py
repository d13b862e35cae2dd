"""A flood of bad frames against ``pymotoros sim``: what it costs in log lines and time
(issue 13, "nothing a client sends can stall the loop"; prints numbers, not a test).

    python bench/bench_log_flood.py                       # 100,000 frames, stderr to a file
    python bench/bench_log_flood.py --stderr unread-pipe  # stderr a pipe nobody reads

It starts ``pymotoros -v sim`` on port-0 ports and sends ``--frames`` requests of an
unknown message type (each answered INVALID/3003, each a refusal the twin would log) to
the motion port in batches of 1,000, reading every reply, then one PING. It prints the
flood's wall time, the replies per second, whether the PING was answered, and the lines
and bytes the twin wrote to stderr.

With ``--stderr unread-pipe`` stderr is a pipe that is read only after the flood, as a
terminal that stopped scrolling or a supervisor that reads its children's output late:
once the pipe's buffer (64 KiB on Linux) is full, every log line blocks the twin's event
loop. A twin that logs every refusal then stops answering (the flood reports how many
replies came before ``--timeout``); one that bounds its log lines
(``runtime/log_limit.py``) does not notice. Run it against another checkout with
``PYTHONPATH=that/src`` to compare.
"""

from __future__ import annotations

import argparse
import re
import socket
import struct
import subprocess
import sys
import tempfile
import time
from typing import IO

UNKNOWN = struct.pack("<iiii", 12, 9999, 2, 0)
"""A whole request of an unknown type: prefix 12, type 9999, SERVICE_REQUEST, reply code 0."""

REPLY_BYTES = 76
"""An INVALID MOTO_MOTION_REPLY on the wire: prefix, header and 60-byte body (§3.1)."""

BATCH = 1000
"""Requests sent before reading their replies."""

PING = struct.pack("<iiii", 12, 1, 2, 0)
"""PING (type 1) as a request (§1.4)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=100_000)
    parser.add_argument("--stderr", choices=("file", "unread-pipe"), default="file")
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds without a reply")
    args = parser.parse_args()

    with tempfile.TemporaryFile() as log:
        run(args, log)


def run(args: argparse.Namespace, log: IO[bytes]) -> None:
    stderr = subprocess.PIPE if args.stderr == "unread-pipe" else log
    command = [sys.executable, "-m", "pymotoros", "-v", "sim", "--motion-port", "0",
               "--state-port", "0", "--io-port", "0", "--http-port", "0"]  # fmt: skip
    sim = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr, text=True)  # noqa: S603
    try:
        assert sim.stdout is not None
        ready = sim.stdout.readline()
        match = re.search(r"motion=(\d+)", ready)
        if match is None:
            sys.exit(f"no ready line from pymotoros sim: {ready!r}")
        sock = socket.create_connection(("127.0.0.1", int(match.group(1))))
        sock.settimeout(args.timeout)
        received = 0
        start = time.perf_counter()
        stalled = False
        try:
            for sent in range(BATCH, args.frames + BATCH, BATCH):
                sock.sendall(UNKNOWN * BATCH)
                while received < sent * REPLY_BYTES:
                    data = sock.recv(1 << 20)
                    if not data:
                        sys.exit("the twin closed the connection")
                    received += len(data)
            flood = time.perf_counter() - start
            sock.sendall(PING)
            answered = len(sock.recv(1 << 16)) > 0
        except TimeoutError:
            stalled = True
            flood = time.perf_counter() - start
            answered = False
        sock.close()
    finally:
        sim.terminate()
        _, err = sim.communicate(timeout=30)
    if args.stderr == "unread-pipe":
        text = err.encode() if isinstance(err, str) else (err or b"")
    else:
        log.seek(0)
        text = log.read()
    replies = received // REPLY_BYTES
    print(f"stderr={args.stderr} frames={args.frames:,} replies={replies:,}")
    if stalled:
        print(f"STALLED: no reply for {args.timeout:g} s after {replies:,} replies")
    else:
        print(f"flood {flood:.2f} s ({replies / flood:,.0f} replies/s), ping answered: {answered}")
    print(f"stderr: {len(text.splitlines()):,} lines, {len(text):,} bytes")


if __name__ == "__main__":
    main()
