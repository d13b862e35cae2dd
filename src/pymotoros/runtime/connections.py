"""Connection slots and the MotoROS replacement rules (reference §2.2), plus socket set-up.

MotoROS serves 1 motion, 4 state and 1 IO client. When a client arrives and every
slot is taken, it looks at the *motion* queues: if increments are queued (the robot
is moving) the newcomer is closed at once; otherwise the client in slot 0 is closed
and the newcomer takes its slot. :class:`SlotTable` is that rule as a small pure
object; the servers act on its :class:`Admission`.
"""

from __future__ import annotations

import asyncio
import enum
import logging
import socket
from dataclasses import dataclass
from typing import Final, Generic, TypeVar

__all__ = [
    "IO_CLIENTS",
    "MOTION_CLIENTS",
    "STATE_CLIENTS",
    "Admission",
    "AdmissionKind",
    "SlotTable",
    "configure_socket",
    "peer_name",
]

logger = logging.getLogger(__name__)

MOTION_CLIENTS: Final = 1
"""Motion connections MotoROS accepts (§2.2)."""

STATE_CLIENTS: Final = 4
"""State connections MotoROS accepts (§2.2)."""

IO_CLIENTS: Final = 1
"""IO connections MotoROS accepts (§2.2)."""

T = TypeVar("T")


class AdmissionKind(enum.Enum):
    ACCEPT = "accept"
    """A free slot."""
    REPLACE = "replace"
    """All slots taken, nothing queued: the client in slot 0 is closed and replaced."""
    REFUSE = "refuse"
    """All slots taken and motion is queued: the newcomer is closed at once."""


@dataclass(frozen=True, slots=True)
class Admission(Generic[T]):
    kind: AdmissionKind
    slot: int
    evicted: T | None = None


class SlotTable(Generic[T]):
    """``capacity`` numbered slots holding connection handles."""

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"capacity must be at least 1, got {capacity}")
        self._slots: list[T | None] = [None] * capacity

    @property
    def capacity(self) -> int:
        return len(self._slots)

    def __len__(self) -> int:
        return sum(1 for s in self._slots if s is not None)

    def occupants(self) -> list[T]:
        return [s for s in self._slots if s is not None]

    def admit(self, newcomer: T, motion_queued: bool) -> Admission[T]:
        """Apply the §2.2 rule; on ACCEPT/REPLACE the newcomer now holds ``slot``."""
        for index, occupant in enumerate(self._slots):
            if occupant is None:
                self._slots[index] = newcomer
                return Admission(AdmissionKind.ACCEPT, index)
        if motion_queued:
            return Admission(AdmissionKind.REFUSE, -1)
        evicted = self._slots[0]
        self._slots[0] = newcomer
        return Admission(AdmissionKind.REPLACE, 0, evicted)

    def release(self, occupant: T) -> bool:
        """Free the slot ``occupant`` holds; False if it holds none (already replaced)."""
        for index, current in enumerate(self._slots):
            if current is occupant:
                self._slots[index] = None
                return True
        return False


def configure_socket(writer: asyncio.StreamWriter) -> None:
    """TCP_NODELAY and SO_KEEPALIVE, as MotoROS sets on every accepted socket (§2.2)."""
    sock = writer.get_extra_info("socket")
    if sock is None:
        return
    try:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
    except OSError as exc:  # MotoROS only logs this failure too
        logger.warning("could not set TCP_NODELAY/SO_KEEPALIVE: %s", exc)


def peer_name(writer: asyncio.StreamWriter) -> str:
    peer = writer.get_extra_info("peername")
    if isinstance(peer, tuple) and len(peer) >= 2:
        return f"{peer[0]}:{peer[1]}"
    return str(peer)
