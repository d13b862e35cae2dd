"""Message construction's reference route: every field checked one by one.

The library checks a message in one function (``bind_check`` in
``pymotoros.protocol.messages._base``): the exact types compared at once and the ranges
tested by ``struct`` packing, anything else walked field by field. Here is the plain
definition it must agree with, wording and all, written without ``struct`` for the
integers: each field in wire order, an array made a tuple of exactly 10 values, a float
any int or float (not a bool) that float32 can hold, an integer any int within int32
or uint32.
"""

from __future__ import annotations

import struct
from typing import Any

from pymotoros.errors import LocalProtocolError
from pymotoros.protocol.constants import INT32_MAX, INT32_MIN, MAX_JOINTS, UINT32_MAX
from pymotoros.protocol.messages._base import F32, I32, JOINTS, Message


def _check_int(owner: str, name: str, value: object, signed: bool) -> None:
    if not isinstance(value, int):
        raise LocalProtocolError(f"{owner}.{name} must be an int, not {type(value).__name__}")
    low, high = (INT32_MIN, INT32_MAX) if signed else (0, UINT32_MAX)
    if not low <= value <= high:
        raise LocalProtocolError(
            f"{owner}.{name} = {value} does not fit in {'int32' if signed else 'uint32'}"
        )


def _check_float(owner: str, name: str, value: object) -> None:
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise LocalProtocolError(f"{owner}.{name} must be a float, not {type(value).__name__}")
    try:
        struct.pack("<f", value)
    except OverflowError:
        raise LocalProtocolError(f"{owner}.{name} = {value} does not fit in float32") from None


def validated_fields(cls: type[Message], message: Any) -> Any:
    """``message`` checked field by field: itself, or a copy with arrays as tuples."""
    owner = cls.__name__
    values = list(message)
    changed = False
    for index, (name, kind) in enumerate(cls.FIELDS):
        value = values[index]
        if kind is JOINTS:
            joints = tuple(value)
            if len(joints) != MAX_JOINTS:
                raise LocalProtocolError(
                    f"{owner}.{name} has {len(joints)} values; the wire carries exactly "
                    f"{MAX_JOINTS} (use for_joints() to pad)"
                )
            for slot, item in enumerate(joints):
                _check_float(owner, f"{name}[{slot}]", item)
            if joints is not value:
                values[index] = joints
                changed = True
        elif kind is F32:
            _check_float(owner, name, value)
        else:
            _check_int(owner, name, value, kind is I32)
    return tuple.__new__(cls, values) if changed else message
