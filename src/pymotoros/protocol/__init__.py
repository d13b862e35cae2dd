"""Simple Message as MotoROS speaks it: sans-I/O codec (bytes in, typed messages out).

Nothing here opens a socket, reads a clock or imports asyncio; the servers in
``pymotoros.runtime`` and the client in ``pymotoros.client`` do the I/O and call
into this package. See ``docs/protocol.md`` for the message catalogue.
"""

from pymotoros.protocol import messages
from pymotoros.protocol.constants import (
    HEADER_SIZE,
    MAX_GROUPS,
    MAX_JOINTS,
    MAX_LENGTH_PREFIX,
    MAX_PULSE_AXES,
    MAX_WIRE_MESSAGE_SIZE,
    PREFIX_SIZE,
    TCP_PORT_IO,
    TCP_PORT_MOTION,
    TCP_PORT_STATE,
    ByteOrder,
    CommType,
    InvalidSubcode,
    IoResultCode,
    MotionCommand,
    MsgType,
    NotReadySubcode,
    Port,
    ReplyType,
    ResultCode,
    ValidFields,
    subcode_meaning,
)
from pymotoros.protocol.framing import (
    Frame,
    FrameDecoder,
    decode_reply,
    decode_request,
    encode,
    encode_frame,
    header_problem,
)
from pymotoros.protocol.messages import *  # noqa: F403 - re-exports messages.__all__
from pymotoros.protocol.sizes import Accept, Close, Reject, Verdict, check_request

__all__ = [
    "HEADER_SIZE",
    "MAX_GROUPS",
    "MAX_JOINTS",
    "MAX_LENGTH_PREFIX",
    "MAX_PULSE_AXES",
    "MAX_WIRE_MESSAGE_SIZE",
    "PREFIX_SIZE",
    "TCP_PORT_IO",
    "TCP_PORT_MOTION",
    "TCP_PORT_STATE",
    "Accept",
    "ByteOrder",
    "Close",
    "CommType",
    "Frame",
    "FrameDecoder",
    "InvalidSubcode",
    "IoResultCode",
    "MotionCommand",
    "MsgType",
    "NotReadySubcode",
    "Port",
    "Reject",
    "ReplyType",
    "ResultCode",
    "ValidFields",
    "Verdict",
    "check_request",
    "decode_reply",
    "decode_request",
    "encode",
    "encode_frame",
    "header_problem",
    "subcode_meaning",
]
__all__ += messages.__all__  # every message class, without listing it here
