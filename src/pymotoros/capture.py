"""The pcapng writing core of the session recorder, shared by the client and the twin.

A :class:`SessionRecorder` writes packets to one pcapng file that Wireshark and
tshark open as TCP traffic: each connection (a :class:`Flow`) gets synthetic
loopback IPv4/TCP headers with its ports, a three-way handshake, sequence and
acknowledgement numbers that follow the bytes in each direction, and the time each
chunk was written or read. So the Simple Message dissectors (by port
50240/50241/50242) decode it, and :mod:`pymotoros.client.recording` reads it back.

The client records its side (:mod:`pymotoros.client.recorder`, ``--record``); the
twin's servers record theirs (``pymotoros sim --record``), through the one hook
every server read and write passes (:class:`pymotoros.runtime.tcp.Connection`).
This module sits outside both layers so that each can import it: it knows nothing
but bytes, ports and dpkt.

Why dpkt: a maintained packet library that writes pcapng and builds IP/TCP headers
(checksums included); python-pcapng writes pcapng blocks but builds no headers.
"""

from __future__ import annotations

import itertools
import socket
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO, Final

import dpkt
import dpkt.pcapng

__all__ = ["CLIENT_IP", "FIRST_CLIENT_PORT", "SERVER_IP", "Flow", "SessionRecorder"]

CLIENT_IP: Final = "127.0.0.1"
SERVER_IP: Final = "127.0.0.2"
"""Synthetic addresses: loopback, client and controller told apart."""
FIRST_CLIENT_PORT: Final = 49152
"""Start of the IANA dynamic port range, for the synthetic client ports."""
_ISN: Final = 1000
"""Initial sequence number of each direction (any value works; Wireshark shows relative)."""


class SessionRecorder:
    """Writes packets to one pcapng file; thread-safe (the sync facade's loop thread)."""

    def __init__(self, path: str | Path, *, clock: Callable[[], float] = time.time) -> None:
        self.path = Path(path)
        self._file: IO[bytes] = self.path.open("wb")
        self._writer = dpkt.pcapng.Writer(self._file, linktype=dpkt.pcap.DLT_EN10MB)
        self._clock = clock
        self._lock = threading.Lock()
        self._ports = itertools.count(FIRST_CLIENT_PORT)
        self.packets = 0

    def flow(self, server_port: int, client_port: int | None = None) -> Flow:
        """A new connection to ``server_port``: writes its handshake.

        ``client_port`` is the client's real port when the recording side knows it
        (the twin's servers: the peer's port); by default a made-up ephemeral one.
        """
        return Flow(self, next(self._ports) if client_port is None else client_port, server_port)

    def write(
        self,
        src: tuple[str, int],
        dst: tuple[str, int],
        seq: int,
        ack: int,
        flags: int,
        payload: bytes = b"",
    ) -> None:
        tcp = dpkt.tcp.TCP(
            sport=src[1], dport=dst[1], seq=seq, ack=ack, flags=flags, win=65535, data=payload
        )
        ip = dpkt.ip.IP(
            src=socket.inet_aton(src[0]),
            dst=socket.inet_aton(dst[0]),
            p=dpkt.ip.IP_PROTO_TCP,
            data=tcp,
            ttl=64,
        )
        ip.len = len(ip)  # header + TCP; dpkt fills the checksums when packing
        eth = dpkt.ethernet.Ethernet(
            src=b"\x02\x00\x00\x00\x00\x01" if src[0] == CLIENT_IP else b"\x02\x00\x00\x00\x00\x02",
            dst=b"\x02\x00\x00\x00\x00\x02" if src[0] == CLIENT_IP else b"\x02\x00\x00\x00\x00\x01",
            type=dpkt.ethernet.ETH_TYPE_IP,
            data=ip,
        )
        with self._lock:
            if self._file.closed:
                return
            self._writer.writepkt(bytes(eth), ts=self._clock())
            self.packets += 1

    def close(self) -> None:
        with self._lock:
            if not self._file.closed:
                self._writer.close()


class Flow:
    """One TCP connection in the recording: sequence numbers per direction."""

    def __init__(self, recorder: SessionRecorder, client_port: int, server_port: int) -> None:
        self._rec = recorder
        self.client = (CLIENT_IP, client_port)
        self.server = (SERVER_IP, server_port)
        self._c_seq = _ISN
        self._s_seq = _ISN
        syn, ack = dpkt.tcp.TH_SYN, dpkt.tcp.TH_ACK
        recorder.write(self.client, self.server, self._c_seq, 0, syn)
        recorder.write(self.server, self.client, self._s_seq, self._c_seq + 1, syn | ack)
        self._c_seq += 1
        self._s_seq += 1
        recorder.write(self.client, self.server, self._c_seq, self._s_seq, ack)

    def sent(self, data: bytes) -> None:
        """Bytes the client wrote (client → controller)."""
        flags = dpkt.tcp.TH_PUSH | dpkt.tcp.TH_ACK
        self._rec.write(self.client, self.server, self._c_seq, self._s_seq, flags, bytes(data))
        self._c_seq += len(data)

    def received(self, data: bytes) -> None:
        """Bytes the client read (controller → client)."""
        flags = dpkt.tcp.TH_PUSH | dpkt.tcp.TH_ACK
        self._rec.write(self.server, self.client, self._s_seq, self._c_seq, flags, bytes(data))
        self._s_seq += len(data)

    def closed(self) -> None:
        """The client closed its side (a FIN from the client)."""
        fin = dpkt.tcp.TH_FIN | dpkt.tcp.TH_ACK
        self._rec.write(self.client, self.server, self._c_seq, self._s_seq, fin)

    # The server's view of the same connection: what it reads came from the client,
    # what it writes goes to it. Aliases, so each side's code reads the right way.

    def from_client(self, data: bytes) -> None:
        """Bytes the controller read (client → controller)."""
        self.sent(data)

    def to_client(self, data: bytes) -> None:
        """Bytes the controller wrote (controller → client)."""
        self.received(data)

    def server_closed(self) -> None:
        """The controller closed the connection (a FIN from the controller)."""
        fin = dpkt.tcp.TH_FIN | dpkt.tcp.TH_ACK
        self._rec.write(self.server, self.client, self._s_seq, self._c_seq, fin)
