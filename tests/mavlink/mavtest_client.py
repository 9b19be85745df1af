"""A minimal pymavlink GCS for tests: one UDP socket, one codec, message history.

Uses the dialect's ``MAVLink`` class directly (no mavutil globals), sends as system 255 /
component 190 like MAVProxy unless told otherwise, and collects everything the server sends so
tests can wait for a message with a deadline instead of sleeping.
"""

from __future__ import annotations

import collections
import select
import socket
import time

from pymavlink.dialects.v20 import ardupilotmega as mav


class GcsClient:
    def __init__(self, server_addr, sysid: int = 255, compid: int = 190):
        self.server_addr = server_addr
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.mav = mav.MAVLink(self, srcSystem=sysid, srcComponent=compid)
        self.mav.robust_parsing = True
        self.history: collections.deque = collections.deque(maxlen=20000)
        self._unread: collections.deque = collections.deque(maxlen=5000)

    # pymavlink "file" interface
    def write(self, buf: bytes) -> None:
        self.sock.sendto(buf, self.server_addr)

    def send(self, msg) -> None:
        self.mav.send(msg)

    def send_raw(self, data: bytes) -> None:
        self.sock.sendto(data, self.server_addr)

    def pump(self, timeout_s: float = 0.0) -> list:
        """Read what has arrived (waiting up to timeout_s for the first datagram)."""
        got = []
        r, _, _ = select.select([self.sock], [], [], timeout_s)
        while r:
            try:
                data = self.sock.recv(65535)
            except BlockingIOError:
                break
            for m in self.mav.parse_buffer(data) or []:
                if m.get_type() != "BAD_DATA":
                    got.append(m)
            r, _, _ = select.select([self.sock], [], [], 0)
        self.history.extend(got)
        self._unread.extend(got)
        return got

    def wait(self, mtype: str, cond=None, timeout_s: float = 2.0):
        """First new message of type mtype (matching cond) within timeout_s, else None."""
        end = time.monotonic() + timeout_s
        while True:
            for m in list(self._unread):
                if m.get_type() == mtype and (cond is None or cond(m)):
                    self._unread.remove(m)
                    return m
            if time.monotonic() >= end:
                return None
            self.pump(max(0.0, min(0.05, end - time.monotonic())))

    def collect(self, duration_s: float) -> list:
        end = time.monotonic() + duration_s
        out = []
        while time.monotonic() < end:
            out.extend(self.pump(min(0.05, max(0.0, end - time.monotonic()))))
        return out

    def drain(self) -> None:
        """Forget everything received so far (wait() then sees only newer messages)."""
        self.pump(0.0)
        self._unread.clear()

    def command_long(self, command, p1=0.0, p2=0.0, p3=0.0, p4=0.0, p5=0.0, p6=0.0, p7=0.0,
                     target=(1, 1), timeout_s=2.0):
        """Send COMMAND_LONG and return its COMMAND_ACK (or None)."""
        self.send(mav.MAVLink_command_long_message(target[0], target[1], command, 0,
                                                   p1, p2, p3, p4, p5, p6, p7))
        return self.wait("COMMAND_ACK", lambda m: m.command == command, timeout_s)

    def command_int(self, command, frame, p1=0.0, p2=0.0, p3=0.0, p4=0.0, x=0, y=0, z=0.0,
                    target=(1, 1), timeout_s=2.0):
        self.send(mav.MAVLink_command_int_message(target[0], target[1], frame, command, 0, 0,
                                                  p1, p2, p3, p4, x, y, z))
        return self.wait("COMMAND_ACK", lambda m: m.command == command, timeout_s)

    def close(self) -> None:
        self.sock.close()


def wait_until(predicate, timeout_s: float = 2.0, step_s: float = 0.01) -> bool:
    """Poll predicate until true or timeout (for state another thread updates)."""
    end = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() >= end:
            return False
        time.sleep(step_s)
    return True
