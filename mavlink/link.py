"""A MAVLink link: one socket, one pymavlink codec object, its own counters.

One ``MAVLink`` codec per link (never mavutil's module globals): each link keeps its own
sequence numbers and parser state, and nothing here touches process-wide state. Sockets are
non-blocking; the owner (the GCS server, later the HIL transport) polls ``fileno()`` and calls
``receive()`` when readable and ``flush()`` when a stream link has bytes waiting.

Sending never blocks: a UDP datagram the kernel will not take is counted as dropped; a TCP link
keeps a bounded output buffer and drops whole frames (never half frames) when a client stops
reading, unlike pymavlink's TCP writer, which loses data silently.
"""

from __future__ import annotations

import collections
import errno
import socket
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.endpoints import Endpoint
from silbridge.mavlink.errors import EndpointError
from silbridge.mavlink.framing import FrameDecoder, RxCounters

UDP_MAX_READS_PER_POLL = 256      # bound the work per wake-up so telemetry keeps its schedule
TCP_MAX_OUT_BYTES = 256 * 1024
RCVBUF_BYTES = 1 << 20


@dataclass(slots=True)
class TxCounters:
    tx_msgs: int = 0
    tx_bytes: int = 0
    tx_dropped: int = 0      # frames the socket would not take (buffer full)
    tx_errors: int = 0       # other send errors (e.g. ICMP port unreachable)
    tx_by_id: collections.Counter = field(default_factory=collections.Counter)


class Link:
    """Common part: codec, decoder, counters. Subclasses own the socket."""

    kind = "link"
    datagram = True

    def __init__(self, name: str, sysid: int, compid: int):
        self.name = name
        self.rx = RxCounters()
        self.tx = TxCounters()
        self.rx_by_id: collections.Counter = collections.Counter()
        # The codec writes through self.write(); pymavlink needs a "file" object.
        self.codec = mav.MAVLink(self, srcSystem=sysid, srcComponent=compid)
        self._decoder = FrameDecoder(self.codec, self.rx)
        self.closed = False

    # -- the pymavlink "file" interface -------------------------------------------------------
    def write(self, buf: bytes) -> None:
        raise NotImplementedError

    # -- public ---------------------------------------------------------------------------------
    def send(self, msg: mav.MAVLink_message) -> None:
        before = self.tx.tx_dropped + self.tx.tx_errors
        self.codec.send(msg)
        if self.tx.tx_dropped + self.tx.tx_errors == before:
            self.tx.tx_msgs += 1
            self.tx.tx_by_id[msg.get_msgId()] += 1   # not .id: a field of RAW_IMU, BATTERY_STATUS

    @property
    def can_send(self) -> bool:
        return not self.closed

    def wants_write(self) -> bool:
        return False

    def flush(self) -> None:
        pass

    def _decode(self, data: bytes) -> list[mav.MAVLink_message]:
        msgs = self._decoder.feed(data, self.datagram)
        for m in msgs:
            self.rx_by_id[m.get_msgId()] += 1
        return msgs

    def counters(self) -> dict:
        d = self.rx.as_dict()
        d.update(tx_msgs=self.tx.tx_msgs, tx_bytes=self.tx.tx_bytes,
                 tx_dropped=self.tx.tx_dropped, tx_errors=self.tx.tx_errors,
                 tx_by_id=dict(self.tx.tx_by_id), rx_by_id=dict(self.rx_by_id))
        return d


class UdpLink(Link):
    """udpout (fixed peer) or udpin (peer = last address that sent a valid frame)."""

    def __init__(self, endpoint: Endpoint, sysid: int, compid: int):
        super().__init__(endpoint.url, sysid, compid)
        self.kind = endpoint.kind
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RCVBUF_BYTES)
        except OSError:
            pass
        self.sock.setblocking(False)
        try:
            if endpoint.kind == "udpin":
                self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                self.sock.bind((endpoint.host, endpoint.port))
                self.peer: tuple[str, int] | None = None
            else:
                self.peer = (socket.gethostbyname(endpoint.host), endpoint.port)
                # Loopback targets get a loopback socket: nothing is exposed to the network.
                self.sock.bind(("127.0.0.1" if endpoint.is_loopback else "0.0.0.0", 0))
        except OSError as exc:
            self.sock.close()
            raise EndpointError(f"cannot open {endpoint.url}: {exc.strerror or exc}; "
                                f"pick another port or stop the program using it") from None
        self.local_address = self.sock.getsockname()

    def fileno(self) -> int:
        return self.sock.fileno()

    @property
    def can_send(self) -> bool:
        return not self.closed and self.peer is not None

    def write(self, buf: bytes) -> None:
        if self.peer is None:
            return
        try:
            self.sock.sendto(buf, self.peer)
            self.tx.tx_bytes += len(buf)
        except (BlockingIOError, InterruptedError):
            self.tx.tx_dropped += 1
        except OSError:
            self.tx.tx_errors += 1

    def receive(self) -> list[mav.MAVLink_message]:
        out: list[mav.MAVLink_message] = []
        for _ in range(UDP_MAX_READS_PER_POLL):
            try:
                data, addr = self.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                # ICMP errors from an earlier send surface here on Linux; not a receive failure.
                continue
            msgs = self._decode(data)
            if msgs:
                if self.kind == "udpin":
                    self.peer = addr
                out.extend(msgs)
        return out

    def close(self) -> None:
        self.closed = True
        self.sock.close()


class TcpClientLink(Link):
    """One accepted TCP connection."""

    kind = "tcp"
    datagram = False

    def __init__(self, sock: socket.socket, addr, sysid: int, compid: int):
        super().__init__(f"tcp:{addr[0]}:{addr[1]}", sysid, compid)
        self.sock = sock
        self.sock.setblocking(False)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.peer = addr
        self._out = bytearray()

    def fileno(self) -> int:
        return self.sock.fileno()

    def write(self, buf: bytes) -> None:
        if self.closed:
            return
        if len(self._out) + len(buf) > TCP_MAX_OUT_BYTES:
            self.tx.tx_dropped += 1
            return
        self._out += buf
        self.tx.tx_bytes += len(buf)
        self.flush()

    def wants_write(self) -> bool:
        return bool(self._out) and not self.closed

    def flush(self) -> None:
        while self._out and not self.closed:
            try:
                n = self.sock.send(self._out)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self.close()
                return
            del self._out[:n]

    def receive(self) -> list[mav.MAVLink_message]:
        try:
            data = self.sock.recv(65536)
        except (BlockingIOError, InterruptedError):
            return []
        except OSError:
            self.close()
            return []
        if not data:
            self.close()
            return []
        return self._decode(data)

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.sock.close()


class TcpListener:
    """tcpin: accepts clients; each becomes a TcpClientLink."""

    def __init__(self, endpoint: Endpoint, sysid: int, compid: int):
        self.name = endpoint.url
        self.sysid, self.compid = sysid, compid
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.sock.bind((endpoint.host, endpoint.port))
            self.sock.listen(8)
        except OSError as exc:
            self.sock.close()
            raise EndpointError(f"cannot listen on {endpoint.url}: {exc.strerror or exc}; "
                                f"pick another port or stop the program using it") from None
        self.sock.setblocking(False)
        self.local_address = self.sock.getsockname()

    def fileno(self) -> int:
        return self.sock.fileno()

    def accept(self) -> TcpClientLink | None:
        try:
            sock, addr = self.sock.accept()
        except (BlockingIOError, InterruptedError):
            return None
        except OSError as exc:
            if exc.errno in (errno.EMFILE, errno.ENFILE, errno.ECONNABORTED):
                return None
            raise
        return TcpClientLink(sock, addr, self.sysid, self.compid)

    def close(self) -> None:
        self.sock.close()


def open_endpoint(endpoint: Endpoint, sysid: int, compid: int) -> UdpLink | TcpListener:
    if endpoint.kind == "tcpin":
        return TcpListener(endpoint, sysid, compid)
    return UdpLink(endpoint, sysid, compid)
