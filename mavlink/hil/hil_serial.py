"""The HIL transport over a serial line: `--link-addr serial:/dev/ttyACM0:921600`.

A flight controller board on a desk talks MAVLink on its USB or UART port; the same HIL
messages as over TCP go on the line, framed by MAVLink 2 itself (magic byte, length, CRC),
so a byte lost on the line costs one frame (counted: rx_bad_crc / rx_malformed) and the
decoder resynchronises on the next magic byte. A serial line has no connection: it is "up"
from the moment it is open, which is why the bridge repeats its configuration with every
heartbeat.

SerialChannel offers HilChannel's surface (send, receive, eof, counters, close), opened with
os/termios directly: raw mode, 8N1, no flow control, the given baud rate (a pseudo-terminal,
as the tests use, ignores the rate). Writes are complete or the line is declared lost after
`send_timeout_s` without progress (a board that stopped reading).
"""

from __future__ import annotations

import errno
import os
import termios

from silbridge.mavlink.hil.hil_errors import HilConnectError
from silbridge.mavlink.hil.hil_link import HilLink, WriteTexts

DEFAULT_BAUD = 921600
_RECV_BYTES = 1 << 16
_SERIAL_TEXTS = WriteTexts(
    failed="writing to the serial line failed ({why})",
    failed_hint="the HIL peer is gone ({error})",
    stalled="the serial line took nothing for {timeout_s:g} s",
    stalled_hint="{error}: the board stopped reading; the run stops")


def is_serial(addr: str | None) -> bool:
    return bool(addr) and addr.startswith("serial:")


def parse_serial(addr: str) -> tuple[str, int]:
    """'serial:/dev/ttyACM0:921600' or 'serial:/dev/ttyACM0' -> (path, baud)."""
    rest = addr[len("serial:"):]
    path, sep, baud = rest.rpartition(":")
    if not sep or not baud.isdigit():
        path, baud = rest, str(DEFAULT_BAUD)
    if not path.startswith("/"):
        raise HilConnectError(f"--link-addr {addr!r}: want serial:/dev/PORT[:BAUD], e.g. "
                              f"serial:/dev/ttyACM0:921600")
    return path, int(baud)


def _speed(baud: int) -> int:
    const = getattr(termios, f"B{baud}", None)
    if const is None:
        raise HilConnectError(f"serial baud rate {baud} is not one termios knows; use e.g. "
                              "57600, 115200, 460800, 921600")
    return const


class SerialChannel(HilLink):
    datagram = False
    peer = None

    def __init__(self, path: str, baud: int, codec, send_timeout_s: float = 5.0):
        super().__init__(codec, send_timeout_s)
        self.name = f"serial:{path}:{baud}"
        try:
            self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        except OSError as e:
            raise HilConnectError(f"cannot open serial port {path} ({e.strerror}): check the "
                                  "cable, the device name and that no other program holds "
                                  "it") from None
        try:
            attrs = termios.tcgetattr(self.fd)
            speed = _speed(baud)
            attrs[0] = 0                                    # iflag: raw input
            attrs[1] = 0                                    # oflag: raw output
            attrs[2] = termios.CS8 | termios.CREAD | termios.CLOCAL
            attrs[3] = 0                                    # lflag: no echo, no canonical
            attrs[4] = attrs[5] = speed
            attrs[6][termios.VMIN] = 0
            attrs[6][termios.VTIME] = 0
            termios.tcsetattr(self.fd, termios.TCSANOW, attrs)
        except (termios.error, HilConnectError) as e:
            os.close(self.fd)
            raise HilConnectError(f"cannot configure serial port {path}: {e}") from None

    def fileno(self) -> int:
        return self.fd

    def send(self, frames: list) -> int:
        if not frames or self.eof:
            return 0
        self._send_all(frames, lambda view: os.write(self.fd, view), self.fd, _SERIAL_TEXTS)
        return 0

    def receive(self, timeout_s: float = 0.0) -> list:
        if not self._readable(self.fd, timeout_s):
            return []
        out: list = []
        for _ in range(64):
            try:
                data = os.read(self.fd, _RECV_BYTES)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as e:
                if e.errno == errno.EIO:         # a pseudo-terminal whose other side closed
                    break
                self._lost(f"reading the serial line failed ({e.strerror or e})")
                break
            if not data:
                break
            out += self._decoder.feed(data, False)
        return out

    def close(self) -> None:
        if self.fd >= 0:
            try:
                os.close(self.fd)
            except OSError:
                pass
            self.fd = -1
        self.eof = True


def open_serial(addr: str, codec) -> SerialChannel:
    path, baud = parse_serial(addr)
    return SerialChannel(path, baud, codec)
