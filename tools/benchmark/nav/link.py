"""The byte links the benchmark's client talks over: UDP (our vehicle sends to a port we
bind, as `silbridge sitl --gcs udpout:...` does; we answer its source address) and TCP
(ArduCopter SITL's MAVLink port 5760 + 10 N). One socket each, no pymavlink `mavutil`
(it changes process-wide state): the client owns one MAVLink codec per link.
"""

from __future__ import annotations

import select
import socket
import time


class LinkError(Exception):
    user_facing = True


class UdpLink:
    """Bound to 127.0.0.1:port; replies go to whoever sent last."""

    def __init__(self, port: int):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", port))
        self.peer = None

    def send(self, buf: bytes) -> None:
        if self.peer is not None:
            self.sock.sendto(buf, self.peer)

    def recv(self, timeout_s: float) -> bytes:
        r, _, _ = select.select([self.sock], [], [], timeout_s)
        if not r:
            return b""
        data, self.peer = self.sock.recvfrom(65536)
        return data

    def close(self) -> None:
        self.sock.close()


class TcpLink:
    """A connection to host:port, retried until connect_timeout_s (wall) runs out."""

    def __init__(self, port: int, connect_timeout_s: float = 60.0, alive=lambda: True):
        end = time.monotonic() + connect_timeout_s
        while True:
            try:
                self.sock = socket.create_connection(("127.0.0.1", port), timeout=1.0)
                break
            except OSError:
                if time.monotonic() > end or not alive():
                    raise LinkError(f"no MAVLink on TCP port {port} after "
                                    f"{connect_timeout_s:g} s") from None
                time.sleep(0.1)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.peer = ("127.0.0.1", port)

    def send(self, buf: bytes) -> None:
        self.sock.sendall(buf)

    def recv(self, timeout_s: float) -> bytes:
        r, _, _ = select.select([self.sock], [], [], timeout_s)
        if not r:
            return b""
        data = self.sock.recv(65536)
        if not data:
            raise LinkError("the autopilot closed its MAVLink connection")
        return data

    def close(self) -> None:
        self.sock.close()


def free_udp_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port
