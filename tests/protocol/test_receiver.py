"""MotoROS's receive loop, sans I/O (protocol/receiver.py; reference §1.5)."""

from __future__ import annotations

import struct

import pytest

from pymotoros.protocol.constants import MotionCommand, MsgType, Port
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import MotoMotionCtrl, Ping
from pymotoros.protocol.receiver import RECV_SIZE, MotoRosReceiver, Turn

LE = "<"
CTRL = encode(MotoMotionCtrl(0, 1, MotionCommand.CHECK_QUEUE_CNT), LE)  # 68 bytes
PING = encode(Ping(), LE)  # 16 bytes


def one_read(data: bytes, receiver: MotoRosReceiver | None = None) -> tuple[MotoRosReceiver, Turn]:
    receiver = receiver or MotoRosReceiver(LE, Port.MOTION)
    receiver.feed(data)
    return receiver, receiver.turn()


def test_a_whole_message_in_one_read() -> None:
    receiver, turn = one_read(CTRL)
    assert (turn.frame.msg_type, len(turn.frame.body)) == (MsgType.MOTO_MOTION_CTRL, 52)
    assert (turn.cut, turn.joined, turn.length_mismatch) == (False, False, False)
    assert receiver.wants_read


def test_a_piece_is_cut_and_dropped() -> None:
    receiver, turn = one_read(CTRL[:30])
    assert turn.cut
    assert turn.expected == 68
    assert receiver.read_size == RECV_SIZE  # nothing kept
    _, tail = one_read(CTRL[30:], receiver)
    assert tail.expected is None  # the tail's "type" is unknown: 3003


def test_fewer_than_16_bytes() -> None:
    _, turn = one_read(CTRL[:5])
    assert turn.cut
    assert turn.expected is None
    assert turn.frame.msg_type == 2001 & 0xFF  # one byte of the type, the rest zero-filled


def test_a_wrong_prefix_is_not_read_but_noticed() -> None:
    data = bytearray(CTRL)
    struct.pack_into("<i", data, 0, 999)
    _, turn = one_read(bytes(data))
    assert not turn.cut
    assert turn.prefix == 999
    assert turn.length_mismatch


def test_a_whole_second_message_is_taken_without_a_read() -> None:
    receiver, first = one_read(PING + CTRL)
    assert first.frame.msg_type == MsgType.PING
    assert not receiver.wants_read
    second = receiver.turn()
    assert second.frame.msg_type == MsgType.MOTO_MOTION_CTRL
    assert not second.joined  # it came whole in the first read
    assert receiver.wants_read


def test_a_partial_second_message_is_joined_with_the_next_read() -> None:
    receiver, _ = one_read(PING + CTRL[:10])
    assert receiver.wants_read
    assert receiver.read_size == RECV_SIZE - 10
    _, turn = one_read(CTRL[10:], receiver)
    assert turn.joined
    assert not turn.cut
    assert turn.frame.msg_type == MsgType.MOTO_MOTION_CTRL


def test_an_unknown_type_drops_the_rest_of_the_read() -> None:
    unknown = struct.pack("<iiii", 12, 9999, 2, 0)
    receiver, turn = one_read(unknown + CTRL)
    assert turn.expected is None
    assert receiver.wants_read
    assert receiver.read_size == RECV_SIZE


def test_a_full_ex_padded_to_552_bytes_is_one_message() -> None:
    head = struct.pack("<iiiiii", 548, MsgType.MOTO_JOINT_TRAJ_PT_FULL_EX, 2, 0, 1, 0)
    receiver, turn = one_read(head.ljust(RECV_SIZE, b"\0"))
    assert turn.expected == RECV_SIZE
    assert not turn.length_mismatch
    assert receiver.wants_read
    assert receiver.read_size == RECV_SIZE


def test_reads_are_bounded_and_ordered() -> None:
    receiver = MotoRosReceiver(LE, Port.MOTION)
    with pytest.raises(RuntimeError, match="feed a read first"):
        receiver.turn()
    receiver.feed(PING + PING)
    with pytest.raises(RuntimeError, match="take its turn"):
        receiver.feed(PING)
    with pytest.raises(ValueError, match="at most 552"):
        MotoRosReceiver(LE, Port.MOTION).feed(bytes(553))
