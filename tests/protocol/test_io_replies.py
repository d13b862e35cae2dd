"""``IO_REPLIES``: the one pairing of each IO request with its reply (the client waits for it)."""

from __future__ import annotations

from pymotoros.protocol.constants import Port
from pymotoros.protocol.framing import REPLY_CLASSES, REQUEST_CLASSES
from pymotoros.protocol.messages import Role
from pymotoros.protocol.messages.io import IO_REPLIES


def test_every_io_request_has_its_registered_reply() -> None:
    io_requests = {
        cls
        for cls in REQUEST_CLASSES[Port.IO].values()
        if cls.__module__ == "pymotoros.protocol.messages.io"
    }
    assert set(IO_REPLIES) == io_requests
    for request, reply in IO_REPLIES.items():
        assert request.ROLE is Role.REQUEST
        assert reply.ROLE is Role.REPLY
        # The next type, except the M-register replies, which reuse the request's (§1.4).
        assert int(reply.MSG_TYPE) - int(request.MSG_TYPE) in (0, 1), request.__name__
        assert REPLY_CLASSES[Port.IO][reply.MSG_TYPE] is reply
