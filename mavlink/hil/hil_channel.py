"""The socket under the HIL transport: one peer, UDP or TCP, one pymavlink codec.

PX4's simulator convention: the simulator (our bridge) listens, on TCP 4560 by default, and
the autopilot (our FC, PX4 SITL, or an autopilot in HIL mode through a serial-to-TCP bridge)
connects. Over UDP the bridge binds the same address and learns the FC's address from its
first datagram. Sockets are non-blocking; `receive(timeout_s)` waits in select() so the
waiting side sleeps in the kernel instead of spinning.

Sending: over TCP a batch is written completely (lockstep needs every frame) with a bounded
wait for the peer to read; a peer that takes nothing for `send_timeout_s` is lost. Over UDP a
batch goes in datagrams of whole frames (up to 32 KiB); a datagram the kernel refuses is
dropped and counted (as a real-time link would lose it).
"""

from __future__ import annotations

import errno
import os
import select
import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.hil.hil_errors import HilConnectError
from silbridge.mavlink.hil.hil_link import HilLink, WriteTexts

DEFAULT_PORT = 4560
_DGRAM_BYTES = 32 * 1024
_SOCK_BUF_BYTES = 4 << 20
# One TCP read. Not larger: CPython allocates the whole size for every recv() and shrinks it
# to what came, and with 1 MiB that costs a 91-byte read 17.6 us against 2.4 us with 64 KiB
# (2-core VM, socketpair), on the lockstep path PX4's reply takes.
_RECV_BYTES = 1 << 16
_TCP_TEXTS = WriteTexts(
    failed="TCP peer lost while sending ({why})",
    failed_hint="the HIL peer disconnected ({error}); restart it",
    stalled="the TCP peer read nothing for {timeout_s:g} s",
    stalled_hint="{error}: it is hung or stopped; the run stops")


def parse_addr(text: str | None, default_host: str = "127.0.0.1") -> tuple[str, int]:
    """'HOST:PORT', ':PORT' or 'PORT' -> (host, port); None -> the default 127.0.0.1:4560."""
    if not text:
        return default_host, DEFAULT_PORT
    host, sep, port = text.rpartition(":")
    if not sep:
        host, port = "", text
    try:
        port_n = int(port)
    except ValueError:
        raise HilConnectError(f"--link-addr {text!r}: want HOST:PORT, e.g. 127.0.0.1:4560") from None
    if not 0 <= port_n <= 65535:
        raise HilConnectError(f"--link-addr {text!r}: port out of range")
    return host or default_host, port_n


def make_codec(sysid: int, compid: int) -> mav.MAVLink:
    """One codec per link (no module globals); frames are built with msg.pack(codec)."""
    return mav.MAVLink(None, srcSystem=sysid, srcComponent=compid)


def _tune(sock: socket.socket) -> None:
    for opt in (socket.SO_RCVBUF, socket.SO_SNDBUF):
        try:
            sock.setsockopt(socket.SOL_SOCKET, opt, _SOCK_BUF_BYTES)
        except OSError:
            pass
    sock.setblocking(False)


class HilChannel(HilLink):
    """A connected (TCP) or peer-learning (UDP) HIL socket with its codec and counters."""

    def __init__(self, sock: socket.socket, datagram: bool, codec, peer=None,
                 send_timeout_s: float = 5.0):
        super().__init__(codec, send_timeout_s)
        self.sock = sock
        self.datagram = datagram
        self.peer = peer
        _tune(sock)

    def fileno(self) -> int:
        return self.sock.fileno()

    # -- send -------------------------------------------------------------------------------
    def send(self, frames: list) -> int:
        """Send frames (bytes each); returns how many the kernel refused (UDP only)."""
        if not frames or self.eof:
            return 0
        if self.datagram:
            return self._send_udp(frames)
        self._send_all(frames, self.sock.send, self.sock, _TCP_TEXTS)
        return 0

    def _send_udp(self, frames: list) -> int:
        if self.peer is None:
            self.tx_dropped += len(frames)
            return len(frames)
        refused = 0
        chunk: list = []
        size = 0
        for f in frames + [None]:
            if f is not None and size + len(f) <= _DGRAM_BYTES:
                chunk.append(f)
                size += len(f)
                continue
            if chunk:
                try:
                    self.sock.sendto(b"".join(chunk), self.peer)
                    self.tx_frames += len(chunk)
                    self.tx_bytes += size
                except OSError as exc:
                    if exc.errno == errno.ECONNREFUSED:
                        self._lost(f"UDP peer {self.peer} refused the datagram (not listening)")
                        return refused + len(chunk)
                    refused += len(chunk)
                    self.tx_dropped += len(chunk)
            chunk, size = ([f], len(f)) if f is not None else ([], 0)
        return refused

    # -- receive ----------------------------------------------------------------------------
    def receive(self, timeout_s: float = 0.0) -> list:
        """Messages available now, waiting up to timeout_s for the first bytes."""
        if not self._readable(self.sock, timeout_s):
            return []
        out: list = []
        drained = False
        for _ in range(256):      # bound one call's work; the caller comes back
            try:
                if self.datagram:
                    data, addr = self.sock.recvfrom(65536)
                    if self.peer is None:
                        self.peer = addr
                    elif addr != self.peer:
                        continue      # one peer per run: ignore strangers
                else:
                    data = self.sock.recv(_RECV_BYTES)
                    if not data:
                        self._lost("the TCP peer closed the connection")
                        break
                    # A short read took all there was: spare the read that would only say
                    # "nothing more" (an exception, ~1.3 us); what comes later, the next call
                    # reads.
                    drained = len(data) < _RECV_BYTES
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:
                if self.datagram and exc.errno == errno.ECONNREFUSED:
                    continue          # ICMP from an earlier datagram; the peer may come later
                self._lost(f"receive failed ({exc.strerror or exc})")
                break
            out += self._decoder.feed(data, self.datagram)
            if drained:
                break
        return out

    def close(self) -> None:
        try:
            self.sock.close()
        except OSError:
            pass
        self.eof = True


class HilListener:
    """The simulator's side: listen (TCP) or bind (UDP) on (host, port); port 0 picks one."""

    def __init__(self, host: str, port: int, datagram: bool):
        self.datagram = datagram
        try:
            if datagram:
                self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            else:
                self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self.sock.bind((host, port))
            if not datagram:
                self.sock.listen(1)
        except OSError as exc:
            raise HilConnectError(f"cannot listen on {host}:{port} ({exc.strerror or exc}): "
                                  f"another simulator may hold the port; pick one with "
                                  f"--link-addr HOST:PORT") from None
        self.sock.setblocking(False)
        self.addr = self.sock.getsockname()

    def accept(self, codec, timeout_s: float = 0.0) -> HilChannel | None:
        """A channel to the autopilot, or None when none came within timeout_s."""
        if self.datagram:
            ch = HilChannel(self.sock, True, codec)
            self.sock = None          # the channel owns the bound socket now
            return ch
        r, _, _ = select.select([self.sock], [], [], max(0.0, timeout_s))
        if not r:
            return None
        try:
            conn, _ = self.sock.accept()
        except (BlockingIOError, InterruptedError):
            return None
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return HilChannel(conn, False, codec)

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()
            self.sock = None


def connect(host: str, port: int, datagram: bool, codec, timeout_s: float) -> HilChannel:
    """The autopilot's side: connect to the simulator, retrying until timeout_s."""
    if datagram:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(("0.0.0.0" if host not in ("127.0.0.1", "localhost") else "127.0.0.1", 0))
        return HilChannel(sock, True, codec, peer=(socket.gethostbyname(host), port))
    deadline = time.monotonic() + max(0.0, timeout_s)
    while True:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.settimeout(1.0)
            sock.connect((host, port))
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            return HilChannel(sock, False, codec)
        except OSError as exc:
            sock.close()
            if time.monotonic() >= deadline:
                raise HilConnectError(
                    f"no simulator listening on {host}:{port} after {timeout_s:g} s "
                    f"({exc.strerror or exc}): start `silbridge bridge --transport tcp` first, "
                    f"or give its address with --link-addr") from None
            time.sleep(0.05)


def pid() -> int:
    return os.getpid()
