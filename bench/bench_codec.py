"""Codec throughput: frames per second for JOINT_TRAJ_PT_FULL and JOINT_FEEDBACK.

Run:  python bench/bench_codec.py [--seconds 0.5] [--repeat 5]

Prints the best of ``--repeat`` timed rounds for each case, measured in CPU time
of this process; rounds interleave the cases, so that load from other processes
on a shared machine disturbs them alike. Not a test: nothing fails.

Cases
  baseline        bare struct.unpack_from of the whole 148-byte JOINT_FEEDBACK frame
  encode          message object -> whole frame bytes (prefix, header, body)
  decode          frame bytes -> typed message, prefix and header parse included:
                  FrameDecoder.feed + next_reply / next_request (one step), and
                  FrameDecoder.feed + next_frame + decode_reply / decode_request
  decode-stream   one step, 100 frames fed as one chunk (a busy socket)
  check_request   server path: frame -> size rules (sizes.check_request) -> message
"""

from __future__ import annotations

import argparse
import platform
import struct
import sys
import time
from collections.abc import Callable

from pymotoros.protocol import (
    ByteOrder,
    FrameDecoder,
    JointFeedback,
    JointTrajPtFull,
    Port,
    decode_reply,
    decode_request,
    encode,
)
from pymotoros.protocol.sizes import check_request

ORDER = ByteOrder.LITTLE
STREAM_FRAMES = 100


def _calibrate(step: Callable[[], object], seconds: float) -> int:
    """Calls of ``step`` that take about ``seconds`` (bounded doubling)."""
    calls = 1000
    while True:
        start = time.process_time()
        for _ in range(calls):
            step()
        elapsed = time.process_time() - start
        if elapsed >= seconds / 4 or calls >= 1 << 24:
            break
        calls *= 2
    return max(1, int(calls * seconds / max(elapsed, 1e-9)))


def _measure(
    cases: list[tuple[str, Callable[[], object], int]], seconds: float, repeat: int
) -> dict[str, float]:
    """Best frames/s of each case; rounds interleave the cases so load spikes hit all alike."""
    calls = {name: _calibrate(step, seconds) for name, step, _ in cases}
    best = dict.fromkeys(calls, 0.0)
    for _ in range(repeat):
        for name, step, per_call in cases:
            start = time.process_time()
            for _ in range(calls[name]):
                step()
            elapsed = time.process_time() - start
            best[name] = max(best[name], calls[name] * per_call / elapsed)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=0.5, help="length of one timed run")
    parser.add_argument("--repeat", type=int, default=5, help="timed runs per case (best wins)")
    args = parser.parse_args()

    # float32-exact values, so that decoding gives back an equal message
    pos = [0.125, -0.25, 0.375, -0.5, 0.625, -0.75]
    vel = [0.015625, 0.03125, 0.046875, 0.0625, 0.078125, 0.09375]
    feedback = JointFeedback.for_joints(0, pos, vel)
    point = JointTrajPtFull.for_joints(0, 12, 0.25, pos, vel)
    fb_frame = encode(feedback, ORDER)
    pt_frame = encode(point, ORDER)
    fb_stream = fb_frame * STREAM_FRAMES
    pt_stream = pt_frame * STREAM_FRAMES
    whole = struct.Struct("<iiiiiif30f")
    decoder = FrameDecoder(ORDER)

    def decode_feedback() -> object:
        decoder.feed(fb_frame)
        return decoder.next_reply(Port.STATE)

    def decode_point() -> object:
        decoder.feed(pt_frame)
        return decoder.next_request(Port.MOTION)

    def two_step_feedback() -> object:
        decoder.feed(fb_frame)
        frame = decoder.next_frame()
        assert frame is not None
        return decode_reply(frame, ORDER, Port.STATE)

    def two_step_point() -> object:
        decoder.feed(pt_frame)
        frame = decoder.next_frame()
        assert frame is not None
        return decode_request(frame, ORDER, Port.MOTION)

    def stream(
        data: bytes, next_message: Callable[[Port], object], port: Port
    ) -> Callable[[], None]:
        def run() -> None:
            decoder.feed(data)
            for _ in range(STREAM_FRAMES):
                next_message(port)

        return run

    def check_point() -> object:
        decoder.feed(pt_frame)
        frame = decoder.next_frame()
        assert frame is not None
        return check_request(frame, ORDER, Port.MOTION)

    assert decode_feedback() == feedback
    assert decode_point() == point
    assert two_step_feedback() == feedback
    assert two_step_point() == point

    cases: list[tuple[str, Callable[[], object], int]] = [
        ("baseline struct.unpack_from JOINT_FEEDBACK", lambda: whole.unpack_from(fb_frame), 1),
        ("encode JOINT_TRAJ_PT_FULL", lambda: encode(point, ORDER), 1),
        ("encode JOINT_FEEDBACK", lambda: encode(feedback, ORDER), 1),
        ("decode JOINT_TRAJ_PT_FULL (next_request)", decode_point, 1),
        ("decode JOINT_FEEDBACK (next_reply)", decode_feedback, 1),
        ("decode JOINT_TRAJ_PT_FULL (next_frame+decode_request)", two_step_point, 1),
        ("decode JOINT_FEEDBACK (next_frame+decode_reply)", two_step_feedback, 1),
        (
            f"decode-stream JOINT_TRAJ_PT_FULL ({STREAM_FRAMES}/chunk)",
            stream(pt_stream, decoder.next_request, Port.MOTION),
            STREAM_FRAMES,
        ),
        (
            f"decode-stream JOINT_FEEDBACK ({STREAM_FRAMES}/chunk)",
            stream(fb_stream, decoder.next_reply, Port.STATE),
            STREAM_FRAMES,
        ),
        ("check_request JOINT_TRAJ_PT_FULL", check_point, 1),
    ]
    print(f"python {platform.python_version()} on {platform.machine()}, {sys.platform}")
    print(f"best of {args.repeat} runs of {args.seconds} s each\n")
    for name, rate in _measure(cases, args.seconds, args.repeat).items():
        print(f"{name:<56} {rate:>12,.0f} frames/s")


if __name__ == "__main__":
    main()
